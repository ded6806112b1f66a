// The function language: implicit surfaces as people type them in GeoGebra, compiled to a Tape.
//
//   x^2 + y^2 + z^2 + 2cos(2x) = 5        sqrt(x²+y²) − a = |z|        (x+1)(x−1) = y z
//
// An input is `lhs = rhs` (the function lhs - rhs, the surface where it is 0) or a bare expression
// (= 0). Reference, in the order the parser applies it:
// - Numbers `2`, `.5`, `1e-3`; constants `pi`, `π`, `e`; variables `x`, `y`, `z`. Any other name is
//   a parameter (`a`, `r1`, `α`), whose value is bound after compilation (expr/parameters.h).
//   A name made only of the letters x, y, z is read letter by letter: `xy` = x y, `xy^2` = x y^2.
// - Operators, loosest first: `+ -`; `* /` and implicit multiplication (`2x`, `2cos(2x)`, `x y`,
//   `(x+1)(x-1)`, `2(x+1)`, `a(x+1)`, `2|x|`), all left-associative (`1/2x` = x/2, as GeoGebra);
//   prefix `-` and `+` (`-x^2` = -(x^2)); `^` and superscripts `²` `³` `⁻¹` `¹⁰`, right-associative
//   (`x^y^z` = x^(y^z)), the exponent may carry a sign (`x^-2`). Unicode `·` `⋅` `×` `÷` `−`.
// - `e^x` is exp(x). A constant exponent p/q with odd q (`x^(1/3)`, `x^(2/3)`) is the real root,
//   defined for negative x as GeoGebra draws it; other non-whole exponents follow std::pow.
// - `|x|` is abs(x); bars nest (`||x|-1|`) and multiply implicitly (`|x||y|`).
// - Functions (parentheses required; `sin²(x)` = sin(x)^2): sin cos tan, asin acos atan (also
//   arcsin arccos arctan), atan2(y, x), sinh cosh tanh, exp, ln and log (natural; log(b, x) is base
//   b), lg = log10, ld = log2, sqrt, cbrt, abs, sgn (sign), floor, ceil, round, min and max (two or
//   more arguments).
// - Refused with a message and a 1-based column (counted in characters): empty input, unbalanced
//   brackets and bars, unknown functions (`foo(x)`), wrong argument counts, misplaced operators
//   (`x^^2`), inequalities (they describe regions, not surfaces), a second `=`, non-finite numbers
//   (`nan`, `inf`, `∞`, `1e999`), invalid UTF-8, and anything over the limits below.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "tape/tape.h"

namespace isomesh {

/// Hard limits on what a compilation accepts, so hostile input costs bounded time and memory.
struct CompileLimits {
    std::size_t max_source_bytes = 64 * 1024;  // expressions
    /// Nesting of brackets, bars, function calls, signs and exponents. Each level takes a few
    /// stack frames: values far above the default (tens of thousands) could exhaust the stack.
    int max_depth = 256;
    /// Instructions emitted (after sharing common subexpressions, before dropping dead ones).
    std::size_t max_instructions = 100000;
    std::size_t max_parameters = 1000;
    std::size_t max_vm_bytes = 16 * 1024 * 1024;  // .vm files (prospero.vm is 149 KB)
};

struct CompileError {
    std::string message;     // the problem, without its position: "unexpected ')'"
    int line = 1;            // 1-based
    int column = 0;          // 1-based, in characters; 0 = no position
    bool multiline = false;  // the source has several lines: to_string names the line

    /// The message with its position: "unexpected ')' at column 12", "... at line 3, column 5".
    std::string to_string() const;
};

struct CompileResult {
    Tape tape;  // valid (Tape::validate() is empty) when ok()
    std::optional<CompileError> error;
    bool ok() const { return !error; }
};

/// Compiles one equation or expression of the language above. Never throws on bad input (only
/// std::bad_alloc); the result's tape is empty when it fails.
CompileResult compile_expression(std::string_view source, const CompileLimits& limits = {});

}  // namespace isomesh
