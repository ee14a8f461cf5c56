# The one place that says which compiler flags each ISA's files get. The per-ISA
# translation units (simd/isa/, simd/testing/isa_*.cpp, the renderer's shading lanes) hold
# explicit instantiations only and are the only files compiled with these flags.
# Contraction stays off in them whatever the global flags: the kernels mirror the scalar
# oracle operation by operation, and watertightness needs both products of a*b - c*d
# rounded (docs/accuracy.md, rule 2).
set(VOLLEY_ISAS sse42 avx2 avx512)
set(VOLLEY_ISA_FLAGS_sse42 -msse4.2)
set(VOLLEY_ISA_FLAGS_avx2 -mavx2 -mfma)
set(VOLLEY_ISA_FLAGS_avx512 -mavx512f -mavx512dq -mavx512bw -mavx512vl -mavx2 -mfma)

# volley_isa_sources(ISA FILE...): FILE... compiled with ISA's flags, without contraction.
function(volley_isa_sources isa)
  if(NOT DEFINED VOLLEY_ISA_FLAGS_${isa})
    message(FATAL_ERROR "volley_isa_sources: unknown ISA '${isa}' (one of ${VOLLEY_ISAS})")
  endif()
  set_source_files_properties(${ARGN} PROPERTIES COMPILE_OPTIONS "${VOLLEY_ISA_FLAGS_${isa}};-ffp-contract=off")
endfunction()
