#pragma once
// Number formatting for the MJCF text the simulator writes (12 significant digits: exact
// enough for millimetre geometry, short enough to read).

#include <iomanip>
#include <sstream>
#include <string>

namespace concert::sim::mjcf {

inline std::string num(double v) {
  std::ostringstream s;
  s << std::setprecision(12) << v;
  return s.str();
}

inline std::string vec(double a, double b, double c) { return num(a) + " " + num(b) + " " + num(c); }

}  // namespace concert::sim::mjcf
