// Preparation of a tape for evaluation. The batch form is register-allocated by a linear scan
// (Poletto & Sarkar, "Linear scan register allocation", TOPLAS 1999) over the SSA code, whose live
// ranges are intervals ending at each value's last use: live values, not instructions, bound the
// scratch memory, so a block of prospero's 7,866 instructions needs only a few dozen registers
// and stays in cache. Fidget's evaluators do the same.
#include "eval/tape_program.h"

#include <cassert>
#include <cmath>
#include <limits>

#include "eval/tape_ops.h"

namespace isomesh {

std::vector<Instruction> substitute_parameters(const Tape& tape, std::span<const double> params) {
    assert(tape.validate().empty() && params.size() == tape.params.size());
    std::vector<Instruction> code = tape.code;
    for (Instruction& ins : code) {
        if (ins.op != Op::Param) continue;
        ins = {Op::Const, 0, 0, params[static_cast<std::size_t>(ins.imm)]};
    }
    return code;
}

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

/// Slots reachable from the output.
std::vector<bool> live_slots(std::span<const Instruction> code) {
    std::vector<bool> live(code.size(), false);
    live.back() = true;
    for (std::size_t i = code.size(); i-- > 0;) {
        if (!live[i] || is_leaf(code[i].op)) continue;
        live[code[i].a] = true;
        if (is_binary(code[i].op)) live[code[i].b] = true;
    }
    return live;
}

/// How a live instruction reads its operands: binary operations take one constant operand as an
/// immediate.
BatchForm form_of(std::span<const Instruction> code, const Instruction& ins) {
    if (!is_binary(ins.op)) return BatchForm::Registers;
    if (code[ins.b].op == Op::Const) return BatchForm::ImmediateB;
    if (code[ins.a].op == Op::Const) return BatchForm::ImmediateA;
    return BatchForm::Registers;
}

class RegisterAllocator {
  public:
    std::uint32_t allocate() {
        if (free_.empty()) return next_++;
        std::uint32_t r = free_.back();  // the most recently freed register is the warmest
        free_.pop_back();
        return r;
    }
    void release(std::uint32_t r) {
        if (r >= kFirstScratchRegister) free_.push_back(r);
    }
    std::uint32_t used() const { return next_ - kFirstScratchRegister; }

  private:
    std::uint32_t next_ = kFirstScratchRegister;
    std::vector<std::uint32_t> free_;
};

}  // namespace

TapeProgram make_program(std::vector<Instruction> code) {
    assert(!code.empty());
    TapeProgram program;
    program.code = std::move(code);
    std::span<const Instruction> c = program.code;
    const std::size_t n = c.size();
    const std::size_t output = n - 1;
    std::vector<bool> live = live_slots(c);
    program.steps.reserve(n);

    // Which values must sit in a register, and the last instruction reading each.
    std::vector<bool> in_register(n, false);
    std::vector<std::size_t> last_use(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const Instruction& ins = c[i];
        if (!live[i] || is_leaf(ins.op)) continue;
        if (is_choice(ins.op)) program.choice_slots.push_back(static_cast<std::uint32_t>(i));
        BatchForm form = form_of(c, ins);
        if (form != BatchForm::ImmediateA) in_register[ins.a] = true, last_use[ins.a] = i;
        if (is_binary(ins.op) && form != BatchForm::ImmediateB)
            in_register[ins.b] = true, last_use[ins.b] = i;
    }

    RegisterAllocator registers;
    std::vector<std::uint32_t> reg(n, kNone);
    for (std::size_t i = 0; i < n; ++i) {
        const Instruction& ins = c[i];
        if (!live[i]) continue;
        bool is_variable = ins.op >= Op::VarX && ins.op <= Op::VarZ;
        if (i != output) {
            if (is_variable) {
                reg[i] = static_cast<std::uint32_t>(ins.op) - static_cast<std::uint32_t>(Op::VarX);
                continue;
            }
            if (ins.op == Op::Const && !in_register[i]) continue;  // read as an immediate only
        }
        const BatchForm form = form_of(c, ins);
        std::uint32_t a = 0, b = 0;
        double imm = ins.imm;
        if (is_variable)
            a = static_cast<std::uint32_t>(ins.op) - static_cast<std::uint32_t>(Op::VarX);
        if (!is_leaf(ins.op)) {
            a = form == BatchForm::ImmediateA ? 0 : reg[ins.a];
            b = is_binary(ins.op) && form != BatchForm::ImmediateB ? reg[ins.b] : 0;
            if (form == BatchForm::ImmediateA) imm = c[ins.a].imm;
            if (form == BatchForm::ImmediateB) imm = c[ins.b].imm;
            if (form != BatchForm::Registers && !std::isfinite(imm))
                program.finite_immediates = false;
        }
        // The result gets its register before the operands' are released, so a step never
        // writes an array it reads (run_batch_steps' precondition).
        const std::uint32_t out = i == output ? kOutputRegister : registers.allocate();
        // Written field by field in place: a step assembled on the stack and then copied stalls
        // on store forwarding, which dominated the cost of push().
        BatchStep& step = program.steps.emplace_back();
        step.op = ins.op;
        step.form = form;
        step.out = out;
        step.a = a;
        step.b = b;
        step.imm = imm;
        reg[i] = out;
        if (is_leaf(ins.op)) continue;
        if (form != BatchForm::ImmediateA && last_use[ins.a] == i) registers.release(reg[ins.a]);
        if (is_binary(ins.op) && form != BatchForm::ImmediateB && ins.b != ins.a &&
            last_use[ins.b] == i)
            registers.release(reg[ins.b]);
    }
    program.scratch_registers = registers.used();
    return program;
}

}  // namespace isomesh
