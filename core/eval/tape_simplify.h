// Tape simplification on a box (Keeter, "Massively parallel rendering of complex closed-form
// implicit surfaces", SIGGRAPH 2020; libfive and Fidget): where interval evaluation over a box
// proves which operand of a min or max is returned, the other operand is dropped, and with it
// every instruction only it used. Big CSG models, made of hundreds of min/max, shrink to the few
// shapes near each box.
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
#include "tape/tape.h"

namespace isomesh {

/// What interval evaluation over a box proves about one min or max instruction.
enum class Choice : std::uint8_t {
    Both,  // either operand may be returned somewhere on the box: keep the instruction
    A,     // operand a is returned everywhere on the box, and b is defined everywhere on it
    B,     // operand b is returned everywhere on the box, and a is defined everywhere on it
};

/// The choice proven for min or max `op` whose operands take their values in a and b on a box:
/// A when a is strictly smaller (min) or larger (max) than b, B the other way round, provided the
/// dropped operand is defined everywhere on the box (NaN propagates through min and max).
inline Choice prove_choice(Op op, const IntervalValue& a, const IntervalValue& b) {
    const Interval& x = a.value;
    const Interval& y = b.value;
    if (x.is_empty() || y.is_empty()) return Choice::Both;
    bool a_wins = op == Op::Min ? x.hi < y.lo : x.lo > y.hi;
    bool b_wins = op == Op::Min ? y.hi < x.lo : y.lo > x.hi;
    if (a_wins && !b.maybe_undefined) return Choice::A;
    if (b_wins && !a.maybe_undefined) return Choice::B;
    return Choice::Both;
}

/// `code` specialised to a box on which the min or max at slot choice_slots[i] is proven to make
/// choices[i]: a min or max with a proven operand is replaced by that operand, and unused
/// instructions are removed. The result computes bit-identical values at every point of the box
/// (NaN where the original is NaN). Returns nullopt when nothing could be dropped.
/// Preconditions: `code` is valid SSA (as Tape::code); choice_slots.size() == choices.size(), each
/// the index of a min or max instruction.
std::optional<std::vector<Instruction>> simplify_on_box(std::span<const Instruction> code,
                                                        std::span<const std::uint32_t> choice_slots,
                                                        std::span<const Choice> choices);

}  // namespace isomesh
