// libFuzzer target: the .vray and .vhit readers, and those of the query files (.vpts,
// .vcnt, .vocc, .vdst, .vclp, .vall), on the same bytes. Bad input must end in
// io::LoadError, without allocating what a header claims; anything else is a finding.
#include <cstdint>

#include "fuzz_file.h"
#include "io/load_error.h"
#include "io/query_files.h"
#include "io/ray_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = volley_fuzz::write_input("in.vray", data, size);
  try {
    (void)volley::io::read_rays(file);
  } catch (const volley::io::LoadError&) {
  }
  try {
    (void)volley::io::read_hits(file);
  } catch (const volley::io::LoadError&) {
  }
  auto quietly = [](auto&& read) {
    try {
      (void)read();
    } catch (const volley::io::LoadError&) {
    }
  };
  quietly([&] { return volley::io::read_points(file); });
  quietly([&] { return volley::io::read_counts(file); });
  quietly([&] { return volley::io::read_occupancy(file); });
  quietly([&] { return volley::io::read_distances(file); });
  quietly([&] { return volley::io::read_closest(file); });
  quietly([&] { return volley::io::read_hit_lists(file); });
  return 0;
}
