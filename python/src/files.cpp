// volley's binary files from Python (python/volley/files.py gives them their NumPy
// dtypes): the C++ readers and writers themselves, so that Python gets the same checks
// and the same messages (io::LoadError -> OSError naming the file and the fault). Records
// travel as rows of bytes, (count, record size) uint8, which files.py views as structured
// arrays; the .vall lists as (offsets, hit rows).
#include "files.h"

#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "io/query_files.h"
#include "io/ray_file.h"

namespace volley::python {
namespace {

template <class T>
py::array_t<std::uint8_t> record_rows(const std::vector<T>& records) {
  py::array_t<std::uint8_t> rows(std::vector<py::ssize_t>{py::ssize_t(records.size()), py::ssize_t(sizeof(T))});
  if (!records.empty()) std::memcpy(rows.mutable_data(), records.data(), records.size() * sizeof(T));
  return rows;
}

/// The records of `rows` ((count, sizeof(T)) uint8, C order: files.py makes them so).
template <class T>
std::vector<T> records_of(const py::array_t<std::uint8_t, py::array::c_style>& rows, const char* what) {
  if (rows.ndim() != 2 || rows.shape(1) != py::ssize_t(sizeof(T)))
    throw py::value_error(std::string(what) + ": expected rows of " + std::to_string(sizeof(T)) + " bytes");
  std::vector<T> records(std::size_t(rows.shape(0)));
  if (!records.empty()) std::memcpy(static_cast<void*>(records.data()), rows.data(), records.size() * sizeof(T));
  return records;
}

using Rows = py::array_t<std::uint8_t, py::array::c_style>;

}  // namespace

void bind_files(py::module_& m) {
  m.def("_read_rays", [](const std::string& p) { return record_rows(io::read_rays(p)); });
  m.def("_read_hits", [](const std::string& p) { return record_rows(io::read_hits(p)); });
  m.def("_read_points", [](const std::string& p) { return record_rows(io::read_points(p)); });
  m.def("_read_counts", [](const std::string& p) { return record_rows(io::read_counts(p)); });
  m.def("_read_occupancy", [](const std::string& p) { return record_rows(io::read_occupancy(p)); });
  m.def("_read_distances", [](const std::string& p) { return record_rows(io::read_distances(p)); });
  m.def("_read_closest", [](const std::string& p) { return record_rows(io::read_closest(p)); });
  m.def("_read_hit_lists", [](const std::string& p) {
    const HitLists lists = io::read_hit_lists(p);
    py::array_t<std::uint64_t> offsets(py::ssize_t(lists.offsets.size()));
    for (std::size_t i = 0; i < lists.offsets.size(); ++i) offsets.mutable_data()[i] = lists.offsets[i];
    return py::make_tuple(offsets, record_rows(lists.hits));
  });

  m.def("_write_rays", [](const std::string& p, const Rows& r) { io::write_rays(p, records_of<Ray>(r, "rays")); });
  m.def("_write_hits", [](const std::string& p, const Rows& r) { io::write_hits(p, records_of<Hit>(r, "hits")); });
  m.def("_write_points", [](const std::string& p, const Rows& r) {
    const std::vector<float> xyz = records_of<float>(r, "points");
    io::write_points(p, xyz);
  });
  m.def("_write_counts", [](const std::string& p, const Rows& r) { io::write_counts(p, records_of<std::uint32_t>(r, "counts")); });
  m.def("_write_occupancy",
        [](const std::string& p, const Rows& r) { io::write_occupancy(p, records_of<std::uint8_t>(r, "occupancy")); });
  m.def("_write_distances",
        [](const std::string& p, const Rows& r) { io::write_distances(p, records_of<float>(r, "distances")); });
  m.def("_write_closest",
        [](const std::string& p, const Rows& r) { io::write_closest(p, records_of<io::ClosestRecord>(r, "closest")); });
  m.def("_write_hit_lists", [](const std::string& p, const py::array_t<std::uint64_t, py::array::c_style>& offsets,
                               const Rows& hits) {
    HitLists lists;
    lists.offsets.assign(offsets.data(), offsets.data() + offsets.size());
    lists.hits = records_of<Hit>(hits, "hits");
    io::write_hit_lists(p, lists);
  });
}

}  // namespace volley::python
