// The evaluator of a tape field (tape_field.h): runs the top of a stack of programs, the tape
// specialised by each push(), with the kernels of batch_kernels.h (point values),
// interval_kernels.h (intervals and interval gradients, one box or eight at a time) and
// point_kernels.h (values with gradients), or with the reference evaluation alone.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "eval/evaluator.h"
#include "eval/interval_kernels.h"
#include "eval/point_kernels.h"
#include "eval/reference_evaluation.h"
#include "eval/tape_field.h"
#include "eval/tape_program.h"

namespace isomesh {

class TapeEvaluator final : public Evaluator {
  public:
    /// `simplify`: push() specialises the program to the box. `reference`: every evaluation runs
    /// the reference evaluation (reference_evaluation.h) instead of the kernels.
    TapeEvaluator(std::shared_ptr<const TapeProgram> program, bool simplify, bool reference);

    double value(const glm::dvec3& p) override;
    void values(const PointBatch& points, std::span<double> out) override;
    IntervalValue interval(const Box& box) override;
    ValueGradient value_gradient(const glm::dvec3& p) override;
    IntervalGradient interval_gradient(const Box& box) override;
    void value_gradients(const PointBatch& points, std::span<ValueGradient> out) override;
    void intervals(std::span<const Box> boxes, std::span<IntervalValue> out) override;
    void interval_gradients(std::span<const Box> boxes, std::span<IntervalGradient> out) override;
    void push(const Box& box) override;
    void pop() override;

    /// The number of instructions of the program evaluations run.
    std::size_t active_size() const { return top().code.size(); }
    IntervalKernelCounts kernel_counts() const { return counts_; }

  private:
    const TapeProgram& top() const { return *stack_.back(); }

    /// Evaluates up to W boxes with the interval kernels (Register: IntervalRegister<W> or
    /// GradientRegister<W>), recomputing the lanes they leave to the reference, and keeps the
    /// choices for push().
    template <std::size_t W, class Register, class Result>
    void evaluate_boxes(std::span<const Box> boxes, std::span<Result> out,
                        std::vector<Register>& registers);
    template <class Result, class Narrow, class Few, class Wide>
    void evaluate_batch(std::span<const Box> boxes, std::span<Result> out, Narrow& narrow, Few& few,
                        Wide& wide);
    /// The choices interval evaluation proves on `box` with the top program: those of the last
    /// batch when it held the box, else from a new evaluation.
    std::span<const Choice> choices_on(const Box& box);
    /// The top program specialised to `choices` (itself when they prove nothing).
    std::shared_ptr<const TapeProgram> simplified(std::span<const Choice> choices);
    /// Runs the point-gradient kernel over up to W points (lanes past the last repeat point 0).
    template <std::size_t W>
    void value_gradients(const PointBatch& points, std::span<ValueGradient> out,
                         std::vector<PointRegister<W>>& registers);
    /// Points the batch registers at this evaluator's block memory.
    void prepare_batch_registers(const TapeProgram& program);

    bool simplify_;
    bool reference_;
    std::vector<std::shared_ptr<const TapeProgram>> stack_;
    ReferenceEvaluation reference_evaluation_;

    // Point values.
    std::vector<double> point_registers_;
    // Batch values.
    std::vector<double> scratch_;
    std::vector<const double*> read_;
    std::vector<double*> write_;
    // Point-gradient kernels, one point or kPointLanes at a time.
    std::vector<PointRegister<1>> gradient_point_registers_;
    std::vector<PointRegister<kPointLanes>> gradient_lane_point_registers_;
    // Interval kernels, one box, kIntervalFewLanes or kIntervalLanes at a time.
    std::vector<IntervalRegister<1>> interval_registers_;
    std::vector<IntervalRegister<kIntervalFewLanes>> interval_few_registers_;
    std::vector<IntervalRegister<kIntervalLanes>> interval_lane_registers_;
    std::vector<GradientRegister<1>> gradient_registers_;
    std::vector<GradientRegister<kIntervalFewLanes>> gradient_few_registers_;
    std::vector<GradientRegister<kIntervalLanes>> gradient_lane_registers_;
    // The last boxes evaluated, with the program and the choices (lane-major) of each.
    std::shared_ptr<const TapeProgram> choices_program_;
    std::vector<Box> choices_boxes_;
    std::vector<Choice> choices_;
    IntervalKernelCounts counts_;
    // Programs push() made lately, by the program and the choices they simplify (neighbouring
    // cells mostly prove the same choices): reused rather than rebuilt. Replaced round-robin.
    struct Simplification {
        std::shared_ptr<const TapeProgram> parent;
        std::vector<Choice> choices;
        std::shared_ptr<const TapeProgram> program;
    };
    static constexpr std::size_t kSimplifications = 64;
    std::vector<Simplification> simplifications_;
    std::size_t next_simplification_ = 0;
};

}  // namespace isomesh
