// `isomesh eval`: the value and gradient of a function at a point, or its interval enclosure on a
// box, as one JSON line. A window on what the evaluators compute, for people and scripts.
#include <cstdio>

#include "args.h"
#include "commands.h"
#include "function_input.h"
#include "output.h"

namespace isomesh::cli {

namespace {

constexpr std::string_view kUsage = R"(usage: isomesh eval EXPR --at x,y,z [--param NAME=VALUE]...
       isomesh eval EXPR --box x0,x1,y0,y1,z0,z1 [--param NAME=VALUE]...

Evaluates the function of EXPR, an equation such as 'x^2+y^2+z^2=1' (meaning lhs - rhs) or
'@model.vm' (a Fidget model file), and prints one JSON line:
  --at x,y,z    {"value":v,"gradient":[dx,dy,dz]}
  --box ...     {"interval":[lo,hi],"maybe_discontinuous":b,"maybe_undefined":b}
                (the interval contains every value on the box; null stands for an infinite end)
  --param a=1.5 the value of parameter a (repeat for each parameter)
Undefined values (such as sqrt(-1)) print as null.
)";

constexpr OptionSpec kOptions[] = {
    {"at", true, false}, {"box", true, false}, {"param", true, true}};

nlohmann::ordered_json at_point(Evaluator& evaluator, const glm::dvec3& p) {
    ValueGradient result = evaluator.value_gradient(p);
    nlohmann::ordered_json out;
    out["value"] = result.value;
    out["gradient"] = {result.gradient.x, result.gradient.y, result.gradient.z};
    return out;
}

nlohmann::ordered_json on_box(Evaluator& evaluator, const Box& box) {
    IntervalValue result = evaluator.interval(box);
    nlohmann::ordered_json out;
    out["interval"] = {result.value.lo, result.value.hi};
    out["maybe_discontinuous"] = result.maybe_discontinuous;
    out["maybe_undefined"] = result.maybe_undefined;
    return out;
}

Box parse_box(std::string_view text) {
    std::vector<double> v = parse_numbers(text, 6, "--box");
    Box box{{v[0], v[2], v[4]}, {v[1], v[3], v[5]}};
    if (!(box.lo.x <= box.hi.x && box.lo.y <= box.hi.y && box.lo.z <= box.hi.z))
        throw UsageError("--box: each lower bound must not exceed its upper bound (x0,x1,y0,...)");
    return box;
}

}  // namespace

int run_eval(std::span<const std::string_view> raw_args) {
    Arguments args(raw_args, kOptions);
    if (args.help()) {
        std::fputs(kUsage.data(), stdout);
        return 0;
    }
    if (args.positional().size() != 1)
        throw UsageError("expected one EXPR, got " + std::to_string(args.positional().size()));
    if (args.has("at") == args.has("box"))
        throw UsageError("give either --at x,y,z or --box x0,x1,y0,y1,z0,z1");
    std::optional<glm::dvec3> point;
    std::optional<Box> box;
    if (args.has("at")) {
        std::vector<double> p = parse_numbers(*args.value("at"), 3, "--at");
        point = glm::dvec3(p[0], p[1], p[2]);
    } else {
        box = parse_box(*args.value("box"));
    }
    std::optional<FunctionInput> function =
        load_function(args.positional()[0], args.values("param"));
    if (!function) return 1;
    std::unique_ptr<Evaluator> evaluator = function->field->make_evaluator();
    print_json_line(point ? at_point(*evaluator, *point) : on_box(*evaluator, *box));
    return 0;
}

}  // namespace isomesh::cli
