#include "eval/tape_field.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "eval/tape_evaluator.h"
#include "eval/tape_program.h"

namespace isomesh {

namespace {

class TapeField final : public Field {
  public:
    explicit TapeField(std::shared_ptr<const TapeProgram> program, TapeFieldOptions options)
        : program_(std::move(program)), options_(options) {}

    std::unique_ptr<Evaluator> make_evaluator() const override {
        return std::make_unique<TapeEvaluator>(program_, options_.simplify, options_.reference);
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

IntervalKernelCounts interval_kernel_counts(const Evaluator& evaluator) {
    const auto* tape_evaluator = dynamic_cast<const TapeEvaluator*>(&evaluator);
    return tape_evaluator ? tape_evaluator->kernel_counts() : IntervalKernelCounts{};
}

}  // namespace isomesh
