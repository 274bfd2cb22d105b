// Times the core of ROS laser_line_extraction (LineExtraction::setRangeData + extractLines,
// built from its public sources by bench.sh) on the FLASER scans of CARMEN logs read from
// stdin, as its ROS node calls it: bearings cached once per geometry, ranges in metres, the
// node's default parameters but range_std_dev = 0.01 m (the cm-quantised logs' noise, as pfe
// is told). Prints scans, beams, lines and the median ns a beam over `reps` passes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "laser_line_extraction/line_extraction.h"

int main(int argc, char** argv) {
  const int reps = std::max(1, argc > 1 ? std::atoi(argv[1]) : 11);
  const size_t per_log = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 200;
  // Scans: one vector of ranges (m) per FLASER line; "LOG" lines from bench.sh separate logs.
  std::vector<std::vector<double>> scans;
  std::string line;
  size_t in_log = 0;
  while (std::getline(std::cin, line)) {
    if (line.rfind("LOG", 0) == 0) { in_log = 0; continue; }
    if (line.rfind("FLASER ", 0) != 0 || (per_log && in_log >= per_log)) continue;
    std::istringstream is(line.substr(7));
    size_t n = 0;
    is >> n;
    std::vector<double> r(n);
    for (auto& v : r) is >> v;
    if (!is) continue;
    // Readings at or beyond the scanner's maximum are no return (as pfe's reader does).
    for (auto& v : r) if (!(v < 50.0)) v = 0.0;
    scans.push_back(std::move(r));
    ++in_log;
  }
  if (scans.empty()) { std::fprintf(stderr, "no FLASER scan on stdin\n"); return 2; }
  line_extraction::LineExtraction le;
  le.setBearingVariance(1e-3 * 1e-3);
  le.setRangeVariance(0.01 * 0.01);
  le.setLeastSqAngleThresh(1e-4);
  le.setLeastSqRadiusThresh(1e-4);
  le.setMaxLineGap(0.4);
  le.setMinLineLength(0.5);
  le.setMinRange(0.4);
  le.setMaxRange(10000.0);
  le.setMinSplitDist(0.05);
  le.setOutlierDist(0.05);
  le.setMinLinePoints(9);
  size_t cached_n = 0, beams = 0, lines = 0;
  for (auto& s : scans) beams += s.size();
  auto cache = [&](size_t n) {
    // pfe's CARMEN convention: n odd: -90° + i·180°/(n-1); n even: -90° + i·180°/n.
    std::vector<double> b(n), c(n), sn(n);
    std::vector<unsigned int> idx(n);
    const double step = M_PI / double(n % 2 ? n - 1 : n);
    for (size_t i = 0; i < n; ++i) {
      b[i] = -M_PI / 2 + double(i) * step;
      c[i] = std::cos(b[i]);
      sn[i] = std::sin(b[i]);
      idx[i] = i;
    }
    le.setCachedData(b, c, sn, idx);
    cached_n = n;
  };
  std::vector<double> times;
  for (int pass = 0; pass <= reps; ++pass) {
    size_t found = 0;
    auto t0 = std::chrono::steady_clock::now();
    for (auto& s : scans) {
      if (s.size() != cached_n) cache(s.size());
      std::vector<line_extraction::Line> out;
      le.setRangeData(s);
      le.extractLines(out);
      found += out.size();
    }
    auto dt = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0);
    if (pass > 0) times.push_back(dt.count() / double(beams));
    lines = found;
  }
  std::sort(times.begin(), times.end());
  std::printf("scans %zu beams %zu lines_per_scan %.2f ns_per_beam %.1f\n", scans.size(), beams,
              double(lines) / double(scans.size()), times[times.size() / 2]);
  return 0;
}
