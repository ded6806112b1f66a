#include "eval/tape_evaluator.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "eval/batch_kernels.h"
#include "eval/tape_simplify.h"

namespace isomesh {

namespace {

std::size_t register_count(const TapeProgram& program) {
    return kFirstScratchRegister + program.scratch_registers;
}

bool same_box(const Box& a, const Box& b) {
    return a.lo == b.lo && a.hi == b.hi;
}

/// Sets registers 0-2 to x, y and z over the boxes (with the unit vectors as their gradients);
/// lanes past the last box repeat box 0.
template <std::size_t W, class Register>
void load_boxes(Register* registers, std::span<const Box> boxes) {
    for (std::size_t l = 0; l < W; ++l) {
        const Box& box = boxes[l < boxes.size() ? l : 0];
        for (int axis = 0; axis < 3; ++axis) {
            Register& r = registers[axis];
            r.lo[l] = box.lo[axis];
            r.hi[l] = box.hi[axis];
            r.flags[l] = 0;
            if constexpr (requires { r.grad_lo; }) {
                for (int k = 0; k < 3; ++k) {
                    r.grad_lo[k][l] = k == axis ? 1.0 : 0.0;
                    r.grad_hi[k][l] = k == axis ? 1.0 : 0.0;
                }
            }
        }
    }
}

template <std::size_t W>
IntervalValue lane_result(const IntervalRegister<W>& r, std::size_t l) {
    return {{r.lo[l], r.hi[l]},
            (r.flags[l] & kMaybeDiscontinuous) != 0,
            (r.flags[l] & kMaybeUndefined) != 0};
}

template <std::size_t W>
IntervalGradient lane_result(const GradientRegister<W>& r, std::size_t l) {
    IntervalGradient g;
    g.value = {{r.lo[l], r.hi[l]},
               (r.flags[l] & kMaybeDiscontinuous) != 0,
               (r.flags[l] & kMaybeUndefined) != 0};
    for (int k = 0; k < 3; ++k) g.gradient[k] = {r.grad_lo[k][l], r.grad_hi[k][l]};
    return g;
}

template <std::size_t W>
std::size_t run_kernel(const TapeProgram& p, IntervalRegister<W>* r, Choice* choices) {
    return run_interval_steps(p.steps, r, choices, p.choice_slots.size());
}

template <std::size_t W>
std::size_t run_kernel(const TapeProgram& p, GradientRegister<W>* r, Choice* choices) {
    return run_gradient_steps(p.steps, r, choices, p.choice_slots.size());
}

void run_reference(ReferenceEvaluation& e, const TapeProgram& p, const Box& box,
                   std::span<Choice> choices, IntervalValue& out) {
    out = e.interval(p, box, choices);
}

void run_reference(ReferenceEvaluation& e, const TapeProgram& p, const Box& box,
                   std::span<Choice> choices, IntervalGradient& out) {
    out = e.interval_gradient(p, box, choices);
}

}  // namespace

TapeEvaluator::TapeEvaluator(std::shared_ptr<const TapeProgram> program, bool simplify,
                             bool reference)
    : simplify_(simplify), reference_(reference) {
    stack_.push_back(std::move(program));
}

double TapeEvaluator::value(const glm::dvec3& p) {
    const TapeProgram& program = top();
    if (reference_) return reference_evaluation_.value(program, p);
    point_registers_.resize(std::max(point_registers_.size(), register_count(program)));
    point_registers_[0] = p.x;
    point_registers_[1] = p.y;
    point_registers_[2] = p.z;
    run_point_steps(program.steps, point_registers_.data());
    return point_registers_[kOutputRegister];
}

void TapeEvaluator::values(const PointBatch& points, std::span<double> out) {
    const std::size_t n = points.size();
    assert(points.y.size() == n && points.z.size() == n && out.size() == n);
    const TapeProgram& program = top();
    prepare_batch_registers(program);
    if (n == kSmallBatch) {
        read_[0] = points.x.data();
        read_[1] = points.y.data();
        read_[2] = points.z.data();
        write_[kOutputRegister] = out.data();
        return run_small_batch_steps(program.steps, read_.data(), write_.data());
    }
    for (std::size_t start = 0; start < n; start += kBatchBlock) {
        const std::size_t count = std::min(kBatchBlock, n - start);
        read_[0] = points.x.data() + start;
        read_[1] = points.y.data() + start;
        read_[2] = points.z.data() + start;
        write_[kOutputRegister] = out.data() + start;
        run_batch_steps(program.steps, read_.data(), write_.data(), count);
    }
}

ValueGradient TapeEvaluator::value_gradient(const glm::dvec3& p) {
    if (reference_) return reference_evaluation_.value_gradient(top(), p);
    ValueGradient out;
    value_gradients({{&p.x, 1}, {&p.y, 1}, {&p.z, 1}}, {&out, 1}, gradient_point_registers_);
    return out;
}

void TapeEvaluator::value_gradients(const PointBatch& points, std::span<ValueGradient> out) {
    const std::size_t n = points.size();
    assert(points.y.size() == n && points.z.size() == n && out.size() == n);
    if (reference_) return Evaluator::value_gradients(points, out);
    for (std::size_t start = 0; start < n; start += kPointLanes) {
        const std::size_t count = std::min(kPointLanes, n - start);
        const PointBatch part{points.x.subspan(start, count), points.y.subspan(start, count),
                              points.z.subspan(start, count)};
        if (count == 1)
            value_gradients(part, out.subspan(start, 1), gradient_point_registers_);
        else
            value_gradients(part, out.subspan(start, count), gradient_lane_point_registers_);
    }
}

template <std::size_t W>
void TapeEvaluator::value_gradients(const PointBatch& points, std::span<ValueGradient> out,
                                    std::vector<PointRegister<W>>& registers) {
    const TapeProgram& program = top();
    registers.resize(std::max(registers.size(), register_count(program)));
    for (std::size_t l = 0; l < W; ++l) {
        const std::size_t i = l < points.size() ? l : 0;
        const double p[3] = {points.x[i], points.y[i], points.z[i]};
        for (int axis = 0; axis < 3; ++axis) {
            registers[axis].value[l] = p[axis];
            for (int k = 0; k < 3; ++k) registers[axis].grad[k][l] = k == axis ? 1.0 : 0.0;
        }
    }
    run_point_gradient_steps(program.steps, registers.data());
    const PointRegister<W>& r = registers[kOutputRegister];
    for (std::size_t l = 0; l < points.size(); ++l) {
        const double v = r.value[l];
        if (std::isnan(v))
            out[l] = {v, glm::dvec3(v)};  // no gradient where f is undefined
        else
            out[l] = {v, {r.grad[0][l], r.grad[1][l], r.grad[2][l]}};
    }
}

IntervalValue TapeEvaluator::interval(const Box& box) {
    IntervalValue out;
    intervals({&box, 1}, {&out, 1});
    return out;
}

IntervalGradient TapeEvaluator::interval_gradient(const Box& box) {
    IntervalGradient out;
    interval_gradients({&box, 1}, {&out, 1});
    return out;
}

void TapeEvaluator::intervals(std::span<const Box> boxes, std::span<IntervalValue> out) {
    evaluate_batch(boxes, out, interval_registers_, interval_few_registers_,
                   interval_lane_registers_);
}

void TapeEvaluator::interval_gradients(std::span<const Box> boxes,
                                       std::span<IntervalGradient> out) {
    evaluate_batch(boxes, out, gradient_registers_, gradient_few_registers_,
                   gradient_lane_registers_);
}

template <class Result, class Narrow, class Few, class Wide>
void TapeEvaluator::evaluate_batch(std::span<const Box> boxes, std::span<Result> out,
                                   Narrow& narrow, Few& few, Wide& wide) {
    assert(boxes.size() == out.size());
    if (boxes.size() == 1) return evaluate_boxes<1>(boxes, out, narrow);
    // Whole batches of kIntervalLanes, the rest (at most kIntervalFewLanes) in a narrower one: a
    // cell's 12 edges as 8 + 4 lanes rather than 8 + 8.
    for (std::size_t start = 0; start < boxes.size(); start += kIntervalLanes) {
        const std::size_t count = std::min(kIntervalLanes, boxes.size() - start);
        if (count <= kIntervalFewLanes)
            evaluate_boxes<kIntervalFewLanes>(boxes.subspan(start, count),
                                              out.subspan(start, count), few);
        else
            evaluate_boxes<kIntervalLanes>(boxes.subspan(start, count), out.subspan(start, count),
                                           wide);
    }
}

template <std::size_t W, class Register, class Result>
void TapeEvaluator::evaluate_boxes(std::span<const Box> boxes, std::span<Result> out,
                                   std::vector<Register>& registers) {
    assert(!boxes.empty() && boxes.size() <= W);
    choices_program_ = stack_.back();
    const TapeProgram& program = top();
    const std::size_t choice_count = program.choice_slots.size();
    choices_boxes_.assign(boxes.begin(), boxes.end());
    choices_.resize(W * choice_count);
    if (reference_ || !program.finite_immediates) {
        for (std::size_t l = 0; l < boxes.size(); ++l) {
            std::span<Choice> lane_choices(choices_.data() + l * choice_count, choice_count);
            run_reference(reference_evaluation_, program, boxes[l], lane_choices, out[l]);
        }
        return;
    }
    registers.resize(std::max(registers.size(), register_count(program)));
    load_boxes<W>(registers.data(), boxes);
    counts_.by_reference += run_kernel(program, registers.data(), choices_.data());
    counts_.steps += W * program.steps.size();
    for (std::size_t l = 0; l < boxes.size(); ++l)
        out[l] = lane_result(registers[kOutputRegister], l);
}

std::span<const Choice> TapeEvaluator::choices_on(const Box& box) {
    const std::size_t choice_count = top().choice_slots.size();
    if (choices_program_ == stack_.back()) {
        for (std::size_t l = 0; l < choices_boxes_.size(); ++l)
            if (same_box(choices_boxes_[l], box))
                return {choices_.data() + l * choice_count, choice_count};
    }
    interval(box);
    return {choices_.data(), choice_count};
}

void TapeEvaluator::push(const Box& box) {
    if (!simplify_) return;
    std::shared_ptr<const TapeProgram> current = stack_.back();
    if (!current->choice_slots.empty()) current = simplified(choices_on(box));
    stack_.push_back(std::move(current));
}

std::shared_ptr<const TapeProgram> TapeEvaluator::simplified(std::span<const Choice> choices) {
    const std::shared_ptr<const TapeProgram>& parent = stack_.back();
    for (const Simplification& s : simplifications_) {
        if (s.parent == parent &&
            std::equal(choices.begin(), choices.end(), s.choices.begin(), s.choices.end()))
            return s.program;
    }
    auto code = simplify_on_box(parent->code, parent->choice_slots, choices);
    if (!code) return parent;
    auto program = std::make_shared<const TapeProgram>(make_program(std::move(*code)));
    Simplification entry{parent, {choices.begin(), choices.end()}, program};
    if (simplifications_.size() < kSimplifications)
        simplifications_.push_back(std::move(entry));
    else
        simplifications_[next_simplification_] = std::move(entry);
    next_simplification_ = (next_simplification_ + 1) % kSimplifications;
    return program;
}

void TapeEvaluator::pop() {
    if (!simplify_) return;
    assert(stack_.size() > 1 && "pop() without push()");
    if (stack_.size() > 1) stack_.pop_back();
}

void TapeEvaluator::prepare_batch_registers(const TapeProgram& program) {
    // A scratch register's array depends on its number alone: the pointers are set once for the
    // most registers a program asked for (the refiner evaluates a few points at a time, very
    // often, with one program).
    const std::size_t count = register_count(program);
    if (count <= read_.size()) return;
    scratch_.resize(program.scratch_registers * kBatchBlock);
    read_.resize(count);
    write_.resize(count);
    for (std::size_t r = kFirstScratchRegister; r < count; ++r) {
        write_[r] = scratch_.data() + (r - kFirstScratchRegister) * kBatchBlock;
        read_[r] = write_[r];
    }
}

}  // namespace isomesh
