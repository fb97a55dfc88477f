#pragma once

#include <cstdlib>

namespace concert::nav::detail {

/// Calls visit(col, row) for the cells of the line from cell (c0, r0) to cell (c1, r1)
/// (Bresenham), both ends included, until visit returns false. Returns false when it did.
template <typename Visit>
bool trace_line(int c0, int r0, int c1, int r1, Visit&& visit) {
  const int dc = std::abs(c1 - c0);
  const int dr = -std::abs(r1 - r0);
  const int sc = c0 < c1 ? 1 : -1;
  const int sr = r0 < r1 ? 1 : -1;
  int err = dc + dr;
  while (true) {
    if (!visit(c0, r0)) return false;
    if (c0 == c1 && r0 == r1) return true;
    const int e2 = 2 * err;
    if (e2 >= dr) {
      err += dr;
      c0 += sc;
    }
    if (e2 <= dc) {
      err += dc;
      r0 += sr;
    }
  }
}

}  // namespace concert::nav::detail
