#include "eval/tape_field.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>
#include <string>

#include "eval/forward_mode.h"
#include "eval/interval_math.h"
#include "eval/tape_arithmetic.h"
#include "eval/tape_program.h"
#include "eval/tape_simplify.h"

namespace isomesh {

namespace {

double leaf_value(const Instruction& ins, const glm::dvec3& p) {
    switch (ins.op) {
        case Op::VarX:
            return p.x;
        case Op::VarY:
            return p.y;
        case Op::VarZ:
            return p.z;
        default:
            return ins.imm;  // Const (parameters are bound to constants)
    }
}

IntervalValue leaf_interval(const Instruction& ins, const Box& box) {
    switch (ins.op) {
        case Op::VarX:
            return {{box.lo.x, box.hi.x}, false, false};
        case Op::VarY:
            return {{box.lo.y, box.hi.y}, false, false};
        case Op::VarZ:
            return {{box.lo.z, box.hi.z}, false, false};
        default:
            return interval_constant(ins.imm);
    }
}

/// Evaluates one tape program in every way the Evaluator interface asks for. The stack holds the
/// programs specialised by push(); all evaluations run the top one.
class TapeEvaluator final : public Evaluator {
  public:
    TapeEvaluator(std::shared_ptr<const TapeProgram> program, bool simplify) : simplify_(simplify) {
        stack_.push_back(std::move(program));
    }

    double value(const glm::dvec3& p) override {
        auto leaf = [&p](const Instruction& ins) { return leaf_value(ins, p); };
        return arithmetic::evaluate(std::span(top().code), slots_, leaf).back();
    }

    void values(const PointBatch& points, std::span<double> out) override {
        const std::size_t n = points.size();
        assert(points.y.size() == n && points.z.size() == n && out.size() == n);
        const TapeProgram& program = top();
        prepare_registers(program);
        for (std::size_t start = 0; start < n; start += kBatchBlock) {
            const std::size_t count = std::min(kBatchBlock, n - start);
            read_[0] = points.x.data() + start;
            read_[1] = points.y.data() + start;
            read_[2] = points.z.data() + start;
            write_[kOutputRegister] = out.data() + start;
            run_batch_steps(program.steps, read_.data(), write_.data(), count);
        }
    }

    IntervalValue interval(const Box& box) override { return interval_slots(top(), box).back(); }

    ValueGradient value_gradient(const glm::dvec3& p) override {
        auto leaf = [&p](const Instruction& ins) { return leaf_value(ins, p); };
        forward_mode::Tangent<double> t = forward_mode::differentiate(top().code, duals_, leaf);
        if (std::isnan(t.value))
            return {t.value, glm::dvec3(t.value)};  // no gradient where f is undefined
        return {t.value, {t.grad[0], t.grad[1], t.grad[2]}};
    }

    IntervalGradient interval_gradient(const Box& box) override {
        auto leaf = [&box](const Instruction& ins) { return leaf_interval(ins, box); };
        forward_mode::Tangent<IntervalValue> t =
            forward_mode::differentiate(top().code, interval_duals_, leaf);
        return {t.value, {t.grad[0].value, t.grad[1].value, t.grad[2].value}};
    }

    void push(const Box& box) override {
        if (!simplify_) return;
        std::shared_ptr<const TapeProgram> current = stack_.back();
        if (current->choices != 0) {
            auto simplified = simplify_on_box(current->code, interval_slots(*current, box));
            if (simplified)
                current = std::make_shared<const TapeProgram>(make_program(std::move(*simplified)));
        }
        stack_.push_back(std::move(current));
    }

    void pop() override {
        if (!simplify_) return;
        assert(stack_.size() > 1 && "pop() without push()");
        if (stack_.size() > 1) stack_.pop_back();
    }

    std::size_t active_size() const { return top().code.size(); }

  private:
    const TapeProgram& top() const { return *stack_.back(); }

    /// Interval enclosures of every instruction of `program` over `box`.
    std::span<const IntervalValue> interval_slots(const TapeProgram& program, const Box& box) {
        auto leaf = [&box](const Instruction& ins) { return leaf_interval(ins, box); };
        return arithmetic::evaluate(std::span(program.code), intervals_, leaf);
    }

    /// Points the scratch registers at this evaluator's block memory.
    void prepare_registers(const TapeProgram& program) {
        const std::size_t count = kFirstScratchRegister + program.scratch_registers;
        if (scratch_.size() < program.scratch_registers * kBatchBlock)
            scratch_.resize(program.scratch_registers * kBatchBlock);
        read_.resize(count);
        write_.resize(count);
        for (std::size_t r = kFirstScratchRegister; r < count; ++r) {
            write_[r] = scratch_.data() + (r - kFirstScratchRegister) * kBatchBlock;
            read_[r] = write_[r];
        }
    }

    bool simplify_;
    std::vector<std::shared_ptr<const TapeProgram>> stack_;
    std::vector<double> slots_;
    std::vector<IntervalValue> intervals_;
    std::vector<forward_mode::Tangent<double>> duals_;
    std::vector<forward_mode::Tangent<IntervalValue>> interval_duals_;
    std::vector<double> scratch_;
    std::vector<const double*> read_;
    std::vector<double*> write_;
};

class TapeField final : public Field {
  public:
    explicit TapeField(std::shared_ptr<const TapeProgram> program, TapeFieldOptions options)
        : program_(std::move(program)), options_(options) {}

    std::unique_ptr<Evaluator> make_evaluator() const override {
        return std::make_unique<TapeEvaluator>(program_, options_.simplify);
    }

  private:
    std::shared_ptr<const TapeProgram> program_;
    TapeFieldOptions options_;
};

/// Empty when `tape` can be evaluated with `params`, else what is wrong.
std::string check_tape(const Tape& tape, std::size_t param_count) {
    if (std::string error = tape.validate(); !error.empty()) return "invalid tape: " + error;
    if (param_count != tape.params.size()) {
        return "the tape has " + std::to_string(tape.params.size()) + " parameters but " +
               std::to_string(param_count) + " values were given";
    }
    for (std::size_t i = 0; i < tape.code.size(); ++i) {
        double n = tape.code[i].imm;
        if (tape.code[i].op == Op::PowInt && !(n == std::trunc(n) && std::fabs(n) <= 0x1p30))
            return "invalid tape: bad integer exponent at " + std::to_string(i);
    }
    return {};
}

}  // namespace

std::shared_ptr<const Field> make_tape_field(std::shared_ptr<const Tape> tape,
                                             std::vector<double> params, TapeFieldOptions options) {
    if (!tape) throw std::invalid_argument("make_tape_field: no tape");
    if (std::string error = check_tape(*tape, params.size()); !error.empty())
        throw std::invalid_argument("make_tape_field: " + error);
    auto program =
        std::make_shared<const TapeProgram>(make_program(substitute_parameters(*tape, params)));
    return std::make_shared<TapeField>(std::move(program), options);
}

std::size_t active_tape_size(const Evaluator& evaluator) {
    const auto* tape_evaluator = dynamic_cast<const TapeEvaluator*>(&evaluator);
    return tape_evaluator ? tape_evaluator->active_size() : 0;
}

}  // namespace isomesh
