// Tape simplification on a box (Keeter, "Massively parallel rendering of complex closed-form
// implicit surfaces", SIGGRAPH 2020; libfive and Fidget): where interval evaluation over a box
// proves which operand of a min or max is returned, the other operand is dropped, and with it
// every instruction only it used. Big CSG models, made of hundreds of min/max, shrink to the few
// shapes near each box. Smooth blends (logsumexp) too, where one operand leads by more than the
// cutoff beyond which log_sum_exp returns it unchanged.
//
// Interval evaluation records what it proves at each min and max as a Choice (Fidget's "choices"),
// so simplification needs no second pass over the box: Evaluator::push reuses the choices of the
// interval evaluation that just classified the box.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "eval/interval.h"
#include "tape/op_math.h"
#include "tape/tape.h"

namespace isomesh {

/// What interval evaluation over a box proves about one min, max or logsumexp instruction.
enum class Choice : std::uint8_t {
    Both,  // either operand may be returned somewhere on the box: keep the instruction
    A,     // operand a is returned everywhere on the box, and b is defined everywhere on it
    B,     // operand b is returned everywhere on the box, and a is defined everywhere on it
};

/// True when x wins over y at every point of the box, for choice operation `op` (tape_ops.h):
/// strictly smaller for min, strictly larger for max, larger by more than kLogSumExpCutoff for
/// logsumexp (where log_sum_exp returns it unchanged: the subtraction rounds monotonically, so
/// x.lo - y.hi > cutoff bounds every difference computed at a point).
inline bool always_wins(Op op, const Interval& x, const Interval& y) {
    switch (op) {
        case Op::Min:
            return x.hi < y.lo;
        case Op::Max:
            return x.lo > y.hi;
        default:
            return x.lo - y.hi > kLogSumExpCutoff;
    }
}

/// The choice proven for choice operation `op` whose operands take their values in a and b on a
/// box: A when a always wins (always_wins), B when b does, provided the dropped operand is
/// defined everywhere on the box (NaN propagates through min, max and logsumexp).
inline Choice prove_choice(Op op, const IntervalValue& a, const IntervalValue& b) {
    const Interval& x = a.value;
    const Interval& y = b.value;
    if (x.is_empty() || y.is_empty()) return Choice::Both;
    if (always_wins(op, x, y) && !b.maybe_undefined) return Choice::A;
    if (always_wins(op, y, x) && !a.maybe_undefined) return Choice::B;
    return Choice::Both;
}

/// `code` specialised to a box on which the choice operation at slot choice_slots[i] is proven to
/// make choices[i]: one with a proven operand is replaced by that operand, and unused
/// instructions are removed. The result computes bit-identical values at every point of the box
/// (NaN where the original is NaN). Returns nullopt when nothing could be dropped.
/// Preconditions: `code` is valid SSA (as Tape::code); choice_slots.size() == choices.size(), each
/// the index of a min, max or logsumexp instruction.
std::optional<std::vector<Instruction>> simplify_on_box(std::span<const Instruction> code,
                                                        std::span<const std::uint32_t> choice_slots,
                                                        std::span<const Choice> choices);

}  // namespace isomesh
