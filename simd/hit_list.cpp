#include "simd/hit_list.h"

namespace volley::simd {

void append_hit(std::vector<Hit>& out, const Hit& h) { out.push_back(h); }

}  // namespace volley::simd
