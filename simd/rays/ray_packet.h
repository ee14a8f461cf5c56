// The SoA ray and hit packets, as the kernels name them. The types and helpers live in the
// public header volley/packet.h (one type for the API, the renderer and the kernels);
// these declarations keep the volley::simd:: spellings working.
#pragma once
#include "volley/packet.h"

namespace volley::simd {

using volley::hit_of;
using volley::HitPacket;
using volley::lane_bits;
using volley::load;
using volley::make_inert;
using volley::ray_of;
using volley::RayPacket;
using volley::reset;
using volley::store;

}  // namespace volley::simd
