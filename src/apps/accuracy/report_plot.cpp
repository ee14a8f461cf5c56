// perf/accuracy/accuracy.png: run time against error, one point per configuration, the
// Pareto front marked and labelled (gnuplot, pngcairo).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "accuracy/report.h"

namespace volley::accuracy {
namespace {

bool gnuplot_available() { return std::system("command -v gnuplot > /dev/null 2>&1") == 0; }

std::string short_label(const Config& c) {
  std::string isa(to_string(c.isa));
  return std::string(to_string(c.test)) + " " + isa + " " + name(c.mode) + (c.robust ? "" : " plain");
}

}  // namespace

bool write_plot(const Report& report, const std::filesystem::path& file, std::string& message) {
  namespace fs = std::filesystem;
  if (!gnuplot_available()) {
    message = "gnuplot not found: " + file.string() + " not written (install gnuplot-nox)";
    return false;
  }
  const std::vector<ConfigSummary> s = summarize(report.rows);
  const std::vector<std::size_t> front = pareto_front(s);
  const fs::path dir = fs::temp_directory_path() / ("volley_accuracy_plot_" + std::to_string(getpid()));
  fs::create_directories(dir);
  {
    // One data block per (triangle test, traversal), blank-line separated: gnuplot's `index`.
    std::ofstream points(dir / "points.dat");
    for (TriangleTest test : {TriangleTest::plane, TriangleTest::moller, TriangleTest::watertight})
      for (bool robust : {true, false}) {
        points << "# " << to_string(test) << (robust ? " robust" : " plain") << "\n";
        bool any = false;
        for (const ConfigSummary& c : s)
          if (c.config.test == test && c.config.robust == robust) {
            points << c.ns_per_ray() << " " << c.error_measure() << "\n";
            any = true;
          }
        if (!any) points << "nan nan\n";
        points << "\n\n";
      }
    // Labels of front points close together on both axes are stacked upwards (x1.8 each).
    std::ofstream pareto(dir / "pareto.dat");
    double last_x = 0, last_y = 0;
    int stack = 0;
    for (std::size_t i : front) {
      const double x = s[i].ns_per_ray(), y = s[i].error_measure();
      const bool close = last_x > 0 && x < 1.3 * last_x && y < 3.0 * last_y && y > last_y / 3.0;
      stack = close ? stack + 1 : 0;
      last_x = x, last_y = y;
      pareto << x << " " << y << " " << y * std::pow(1.8, stack) << " \"" << short_label(s[i].config) << "\"\n";
    }
  }
  const fs::path script = dir / "plot.gp";
  {
    std::ofstream gp(script);
    gp << "set terminal pngcairo size 1200,800 font 'sans,10'\n"
       << "set output '" << fs::absolute(file).string() << "'\n"
       << "set title 'volley accuracy: run time against error (one point per test x ISA x mode x traversal)'\n"
       << "set xlabel 'ns per ray (CPU time of one thread, closest hit; " << speed_basis(report.rows) << ")'\n"
       << "set ylabel 'leak rate + worst p99.9 relative t error (log)'\n"
       << "set logscale y\nset logscale x\nset grid\nset key outside right top\n"
       << "set format y '10^{%L}'\n"
       << "plot '" << (dir / "points.dat").string()
       << "' index 0 with points pt 7 ps 1.4 lc rgb '#d62728' title 'plane robust',"
       << " '' index 1 with points pt 6 ps 1.4 lc rgb '#d62728' title 'plane plain',"
       << " '' index 2 with points pt 7 ps 1.4 lc rgb '#1f77b4' title 'moller robust',"
       << " '' index 3 with points pt 6 ps 1.4 lc rgb '#1f77b4' title 'moller plain',"
       << " '' index 4 with points pt 7 ps 1.4 lc rgb '#2ca02c' title 'watertight robust',"
       << " '' index 5 with points pt 6 ps 1.4 lc rgb '#2ca02c' title 'watertight plain',"
       << " '" << (dir / "pareto.dat").string() << "' using 1:2 with steps lw 2 lc rgb 'black' title 'Pareto front',"
       << " '' using 1:3:4 with labels left offset 1,0.6 font 'sans,8' notitle\n";
  }
  const std::string cmd = "gnuplot '" + script.string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  fs::remove_all(dir);
  if (status != 0) {
    message = "gnuplot failed (status " + std::to_string(status) + "): " + file.string() + " not written";
    return false;
  }
  return true;
}

}  // namespace volley::accuracy
