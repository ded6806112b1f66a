#include "eval/tape_simplify.h"

#include <algorithm>
#include <cassert>

#include "eval/tape_ops.h"

namespace isomesh {

std::optional<std::vector<Instruction>> simplify_on_box(std::span<const Instruction> code,
                                                        std::span<const std::uint32_t> choice_slots,
                                                        std::span<const Choice> choices) {
    assert(!code.empty() && choice_slots.size() == choices.size());
    if (std::all_of(choices.begin(), choices.end(), [](Choice c) { return c == Choice::Both; }))
        return std::nullopt;
    const std::size_t n = code.size();
    // forward[i]: the slot whose value slot i always equals on the box (itself, or the proven
    // operand of a min, max or logsumexp, followed transitively: operands come before their uses).
    std::vector<std::uint32_t> forward(n);
    for (std::size_t i = 0; i < n; ++i) forward[i] = static_cast<std::uint32_t>(i);
    for (std::size_t c = 0; c < choices.size(); ++c) {
        const std::uint32_t i = choice_slots[c];
        assert(is_choice(code[i].op));
        if (choices[c] != Choice::Both)
            forward[i] = forward[choices[c] == Choice::A ? code[i].a : code[i].b];
    }

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
