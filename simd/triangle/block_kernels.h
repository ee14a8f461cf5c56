// The kernel forms, generic over the triangle test (moller.h, plane.h, watertight.h):
//  - one ray x blocks (single-ray traversal of incoherent rays), closest hit and any hit;
//  - a packet of K rays x one triangle, and x blocks (coherent packets), closest and any.
// Bodies (ray_block_kernels.h, packet_block_kernels.h, on kernel_forms.h) are templated on
// Arch and instantiated only in the per-ISA files, as simd/isa/kernel_table.h lists them; the
// extern template declarations below keep every other file from instantiating them.
//
// Closest-hit semantics, all forms: triangles are taken in block order, lane order, and a
// triangle replaces the current hit when it is hit with tmin <= t < upper, where upper
// starts as (hit.t < ray.tmax ? hit.t : ray.tmax) and becomes t of each accepted hit. That
// is the scalar oracle's loop exactly (ties keep the earlier triangle unless the test
// itself says otherwise), so the kernels agree with it triangle by triangle.
#pragma once
#include "simd/triangle/packet_block_kernels.h"
#include "simd/triangle/ray_block_kernels.h"
#include "simd/isa/kernel_table.h"

namespace volley::simd {

// Explicit instantiation declarations of the one kernel table (simd/isa/kernel_table.h):
// the definitions live in the per-ISA files only.
VOLLEY_DECLARE_ALL_KERNELS()

}  // namespace volley::simd
