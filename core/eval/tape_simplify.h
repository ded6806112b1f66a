// Tape simplification on a box (Keeter, "Massively parallel rendering of complex closed-form
// implicit surfaces", SIGGRAPH 2020; libfive and Fidget): where interval evaluation over a box
// proves which operand of a min or max is returned, the other operand is dropped, and with it
// every instruction only it used. Big CSG models, made of hundreds of min/max, shrink to the few
// shapes near each box.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "eval/interval.h"
#include "tape/tape.h"

namespace isomesh {

/// `code` specialised to a box on which instruction i takes its values in `slot_values[i]` (the
/// interval evaluator's enclosures over the box): a min or max whose operand a (or b) is proven
/// strictly smaller (or larger) than the other is replaced by that operand, provided the dropped
/// operand is defined everywhere on the box (NaN propagates through min and max); unused
/// instructions are removed. The result computes bit-identical values at every point of the box
/// (NaN where the original is NaN). Returns nullopt when nothing could be dropped.
/// Preconditions: `code` is valid SSA (as Tape::code); slot_values.size() == code.size().
std::optional<std::vector<Instruction>> simplify_on_box(std::span<const Instruction> code,
                                                        std::span<const IntervalValue> slot_values);

}  // namespace isomesh
