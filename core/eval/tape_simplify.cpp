#include "eval/tape_simplify.h"

#include <cassert>
#include <cstdint>

#include "eval/forward_mode.h"
#include "eval/tape_ops.h"

namespace isomesh {

namespace {

/// The operand a min or max at slot `i` always returns on the box, or -1.
int proven_operand(const Instruction& ins, std::span<const IntervalValue> values) {
    const IntervalValue& a = values[ins.a];
    const IntervalValue& b = values[ins.b];
    forward_mode::Pick pick = forward_mode::pick(ins.op, a, b);
    if (pick == forward_mode::Pick::A && !b.maybe_undefined) return 0;
    if (pick == forward_mode::Pick::B && !a.maybe_undefined) return 1;
    return -1;
}

}  // namespace

std::optional<std::vector<Instruction>> simplify_on_box(
    std::span<const Instruction> code, std::span<const IntervalValue> slot_values) {
    assert(!code.empty() && slot_values.size() == code.size());
    const std::size_t n = code.size();
    // forward[i]: the slot whose value slot i always equals on the box (itself, or the proven
    // operand of a min or max, followed transitively).
    std::vector<std::uint32_t> forward(n);
    bool changed = false;
    for (std::size_t i = 0; i < n; ++i) {
        const Instruction& ins = code[i];
        forward[i] = static_cast<std::uint32_t>(i);
        if (ins.op != Op::Min && ins.op != Op::Max) continue;
        int operand = proven_operand(ins, slot_values);
        if (operand < 0) continue;
        forward[i] = forward[operand == 0 ? ins.a : ins.b];
        changed = true;
    }
    if (!changed) return std::nullopt;

    std::vector<bool> live(n, false);
    live[forward[n - 1]] = true;
    for (std::size_t i = n; i-- > 0;) {
        if (!live[i] || is_leaf(code[i].op)) continue;
        assert(forward[i] == i);
        live[forward[code[i].a]] = true;
        if (is_binary(code[i].op)) live[forward[code[i].b]] = true;
    }

    std::vector<Instruction> simplified;
    std::vector<std::uint32_t> renumber(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        if (!live[i]) continue;
        Instruction ins = code[i];
        if (!is_leaf(ins.op)) ins.a = renumber[forward[ins.a]];
        if (is_binary(ins.op)) ins.b = renumber[forward[ins.b]];
        renumber[i] = static_cast<std::uint32_t>(simplified.size());
        simplified.push_back(ins);
    }
    return simplified;
}

}  // namespace isomesh
