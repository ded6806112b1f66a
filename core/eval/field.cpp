#include <limits>

#include "eval/evaluator.h"

namespace isomesh {

Box Field::domain() const {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    return {glm::dvec3(-kInf), glm::dvec3(kInf)};
}

}  // namespace isomesh
