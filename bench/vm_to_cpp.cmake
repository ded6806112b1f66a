# Translates a Fidget .vm model into straight-line C++: the native baseline bench_eval compares the
# tape evaluators with, and the function bench_pipeline's grid baseline samples (grid_baseline.h).
# Run at build time into the build tree (the output for prospero is ~8,000
# lines: generated, never committed).
#   cmake -DVM=model.vm -DNAME=model -DOUT=native_model.cpp -P vm_to_cpp.cmake
# Defines: void native_<NAME>(const double* x, const double* y, const double* z, double* out,
#                             std::size_t n), out[i] = model(x[i], y[i], z[i]).
# min and max are std::min and std::max, as a person writing the model in C++ would. The function
# is compiled for AVX2 too, as the evaluator's loops are (ISOMESH_VECTOR_CLONES).
file(STRINGS "${VM}" lines)
set(unary_neg "-(@A@)")
set(unary_square "@A@ * @A@")
set(unary_sqrt "std::sqrt(@A@)")
set(unary_abs "std::fabs(@A@)")
set(unary_exp "std::exp(@A@)")
set(unary_ln "std::log(@A@)")
set(unary_sin "std::sin(@A@)")
set(unary_cos "std::cos(@A@)")
set(binary_add "@A@ + @B@")
set(binary_sub "@A@ - @B@")
set(binary_mul "@A@ * @B@")
set(binary_div "@A@ / @B@")
set(binary_min "std::min(@A@, @B@)")
set(binary_max "std::max(@A@, @B@)")

set(body "")
set(last "")
foreach(line IN LISTS lines)
  string(STRIP "${line}" line)
  if(line STREQUAL "" OR line MATCHES "^#")
    continue()
  endif()
  string(REGEX REPLACE "[ \t]+" ";" words "${line}")
  list(GET words 0 name)
  list(GET words 1 opcode)
  list(LENGTH words count)
  if(opcode MATCHES "^var-([xyz])$")
    set(expression "${CMAKE_MATCH_1}")
  elseif(opcode STREQUAL "const")
    list(GET words 2 expression)
  elseif(DEFINED unary_${opcode} AND count EQUAL 3)
    list(GET words 2 a)
    string(REPLACE "@A@" "v${a}" expression "${unary_${opcode}}")
  elseif(DEFINED binary_${opcode} AND count EQUAL 4)
    list(GET words 2 a)
    list(GET words 3 b)
    string(REPLACE "@A@" "v${a}" expression "${binary_${opcode}}")
    string(REPLACE "@B@" "v${b}" expression "${expression}")
  else()
    message(FATAL_ERROR "${VM}: cannot translate '${line}'")
  endif()
  string(APPEND body "        const double v${name} = ${expression};\n")
  set(last "v${name}")
endforeach()

file(WRITE "${OUT}" "// Generated from ${VM} by bench/vm_to_cpp.cmake. Do not edit.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include \"eval/batch_kernels.h\"  // ISOMESH_VECTOR_CLONES, as the evaluator's loops

ISOMESH_VECTOR_CLONES void native_${NAME}(const double* xs, const double* ys, const double* zs, double* out,
                    std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        [[maybe_unused]] const double x = xs[i], y = ys[i], z = zs[i];
${body}        out[i] = ${last};
    }
}
")
