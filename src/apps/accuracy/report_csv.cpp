// perf/accuracy/accuracy.csv: one line per (case, configuration) and per image render.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "accuracy/report.h"

namespace volley::accuracy {
namespace {

std::string num(double x) {
  if (std::isnan(x)) return "";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", x);
  return buf;
}

}  // namespace

void write_csv(const Report& report, const std::filesystem::path& file) {
  std::ostringstream out;
  out << "section,set,case,offset,test,isa,mode,traversal,rays,hits,leaks,leak_rate,t_err_samples,t_err_median,"
         "t_err_p999,t_err_max,false_hits,false_misses,nan,seconds,mrays_s,rmse,psnr_db\n";
  for (const Row& r : report.rows) {
    out << "rays," << r.set << "," << r.name << "," << offset_text(r.offset) << "," << to_string(r.config.test) << ","
        << to_string(r.config.isa) << "," << name(r.config.mode) << "," << (r.config.robust ? "robust" : "plain") << ","
        << r.rays << "," << r.hits << "," << (r.closed ? std::to_string(r.leaks) : "") << ","
        << (r.closed ? num(r.leak_rate()) : "") << "," << r.t_error.samples << "," << num(r.t_error.median) << ","
        << num(r.t_error.p999) << "," << num(r.t_error.max) << "," << r.false_hits << "," << r.false_misses << ","
        << r.nan << "," << num(r.seconds) << "," << num(r.mrays()) << ",,\n";
  }
  for (const ImageRow& r : report.images) {
    out << "image,render," << r.scene << ",0," << (r.reference ? "reference" : std::string(to_string(r.test))) << ","
        << to_string(r.isa) << ",,robust," << r.width * r.height << ",,,,,,,,,," << r.nan_pixels << ","
        << num(r.seconds) << ",," << num(r.rmse) << "," << num(r.psnr) << "\n";
  }
  std::ofstream f(file);
  if (!(f << out.str())) throw std::runtime_error(file.string() + ": cannot write the CSV");
}

}  // namespace volley::accuracy
