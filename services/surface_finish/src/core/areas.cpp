#include "surface_finish/areas.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <limits>
#include <optional>

namespace concert::surface_finish {

namespace {

// One connected region of reachable cells, grown from a start cell: every cell is solved from
// a neighbour already in the region (its solution as the IK seed, continuity checked against
// it), breadth first, so a failed cell does not cut off what lies beyond it.
struct Region {
  std::vector<std::optional<Eigen::VectorXd>> q;  // per cell
  int count = 0;
};

Region flood(Reach& reach, const WallFrame& wall, double standoff, double roll, const AreaMap& m, int start,
             const Eigen::VectorXd& q_start, std::vector<std::string>& reasons) {
  Region r;
  r.q.assign(static_cast<std::size_t>(m.nx * m.ny), std::nullopt);
  std::vector<char> tried_from(static_cast<std::size_t>(m.nx * m.ny) * 4, 0);
  r.q[static_cast<std::size_t>(start)] = q_start;
  r.count = 1;
  std::vector<int> queue{start};
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const int c = queue[head];
    const int ix = c % m.nx, iy = c / m.nx;
    const int nb[4][2] = {{ix, iy + 1}, {ix, iy - 1}, {ix + 1, iy}, {ix - 1, iy}};
    for (int d = 0; d < 4; ++d) {
      const int nx = nb[d][0], ny = nb[d][1];
      if (nx < 0 || ny < 0 || nx >= m.nx || ny >= m.ny) continue;
      const int n = ny * m.nx + nx;
      if (r.q[static_cast<std::size_t>(n)] || tried_from[static_cast<std::size_t>(n * 4 + d)]) continue;
      tried_from[static_cast<std::size_t>(n * 4 + d)] = 1;
      const Eigen::VectorXd& seed = *r.q[static_cast<std::size_t>(c)];
      const ReachPose p = reach.solve(Reach::target(wall, m.x_min + nx * m.grid, m.y_min + ny * m.grid, standoff, roll),
                                      wall, seed, &seed, false);
      if (p.ok) {
        r.q[static_cast<std::size_t>(n)] = p.q;
        ++r.count;
        queue.push_back(n);
      } else if (reasons[static_cast<std::size_t>(n)].empty()) {
        reasons[static_cast<std::size_t>(n)] = p.reason;
      }
    }
  }
  return r;
}

// Largest all-true rectangle of a binary grid (histogram method): cells [ix0, ix1] x [iy0, iy1].
struct CellRect {
  int ix0 = 0, ix1 = -1, iy0 = 0, iy1 = -1;
  [[nodiscard]] long area() const { return static_cast<long>(ix1 - ix0 + 1) * (iy1 - iy0 + 1); }
};

CellRect maximal_rectangle(const AreaMap& m) {
  CellRect best;
  std::vector<int> h(static_cast<std::size_t>(m.nx), 0);
  for (int iy = 0; iy < m.ny; ++iy) {
    for (int ix = 0; ix < m.nx; ++ix) h[static_cast<std::size_t>(ix)] = m.cell(ix, iy) ? h[static_cast<std::size_t>(ix)] + 1 : 0;
    std::vector<int> stack;
    for (int ix = 0; ix <= m.nx; ++ix) {
      const int cur = ix < m.nx ? h[static_cast<std::size_t>(ix)] : 0;
      while (!stack.empty() && h[static_cast<std::size_t>(stack.back())] >= cur) {
        const int height = h[static_cast<std::size_t>(stack.back())];
        stack.pop_back();
        const int left = stack.empty() ? 0 : stack.back() + 1;
        CellRect r{left, ix - 1, iy - height + 1, iy};
        if (height > 0 && r.area() > best.area()) best = r;
      }
      stack.push_back(ix);
    }
  }
  return best;
}

}  // namespace

bool AreaMap::covers(const Rect& r, std::string* why) const {
  const double eps = 1e-6;
  for (int iy = 0; iy < ny; ++iy) {
    const double y = y_min + iy * grid;
    if (y < r.y0 - eps || y > r.y1 + eps) continue;
    for (int ix = 0; ix < nx; ++ix) {
      const double x = x_min + ix * grid;
      if (x < r.x0 - eps || x > r.x1 + eps) continue;
      if (!cell(ix, iy)) {
        if (why != nullptr) {
          char b[96];
          std::snprintf(b, sizeof b, "(x, y) = (%.2f, %.2f) m: ", x, y);
          *why = b + reasons[static_cast<std::size_t>(iy * nx + ix)];
        }
        return false;
      }
    }
  }
  // Outside the grid altogether.
  if (r.x0 < x_min - eps || r.x1 > x_min + (nx - 1) * grid + eps || r.y0 < y_min - eps ||
      r.y1 > y_min + (ny - 1) * grid + eps) {
    if (why != nullptr) *why = "outside the searched wall " + Rect{x_min, x_min + (nx - 1) * grid, y_min, y_min + (ny - 1) * grid}.str();
    return false;
  }
  return true;
}

const Eigen::VectorXd& AreaMap::posture_near(double x, double y) const {
  double best = std::numeric_limits<double>::infinity();
  std::size_t at = postures.size();
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      if (!cell(ix, iy)) continue;
      const double d = std::hypot(x_min + ix * grid - x, y_min + iy * grid - y);
      if (d < best) {
        best = d;
        at = static_cast<std::size_t>(iy * nx + ix);
      }
    }
  }
  if (at >= postures.size()) throw FinishError("no reachable cell at model version " + std::to_string(model_version));
  return postures[at];
}

const Area& AreaMap::area(const std::string& id) const {
  for (const Area& a : areas) {
    if (a.id == id) return a;
  }
  std::string known;
  for (const Area& a : areas) known += (known.empty() ? "" : ", ") + a.id;
  throw FinishError("no area '" + id + "' at model version " + std::to_string(model_version) + " (areas: " +
                    (known.empty() ? "none" : known) + ")");
}

AreaMap compute_areas(Reach& reach, const WallFrame& wall, Task task, double standoff, const AreaParams& params) {
  if (!(params.grid > 0.0) || !(params.half_width > 0.0) || !(params.max_height > params.min_height) ||
      params.panels < 1) {
    throw FinishError("area parameters: grid, half_width > 0, max_height > min_height and panels >= 1 needed");
  }
  AreaMap m;
  m.model_version = reach.model().version();
  m.task = task;
  m.standoff = standoff;
  m.wall_distance = wall.distance();
  m.grid = params.grid;
  const int half = static_cast<int>(std::floor(params.half_width / params.grid + 1e-9));
  m.nx = 2 * half + 1;
  m.x_min = -half * params.grid;
  m.ny = static_cast<int>(std::floor((params.max_height - params.min_height) / params.grid + 1e-9)) + 1;
  m.y_min = params.min_height;
  const std::size_t n = static_cast<std::size_t>(m.nx * m.ny);

  // Regions grown from start cells (a column of heights at the centre and a third of the way
  // out each side, solved with restarts), for each of four tool rolls; the region whose largest
  // rectangle is largest wins.
  std::vector<std::string> reasons(n);
  Region best;
  long best_area = -1;
  CellRect best_rect;
  for (const double roll : {0.0, 0.5 * M_PI, M_PI, 1.5 * M_PI}) {
    std::vector<char> covered(n, 0);
    for (const int sx : {half, half - m.nx / 6, half + m.nx / 6}) {
      for (int sy = m.ny / 8; sy < m.ny; sy += std::max(1, m.ny / 6)) {
        const int start = sy * m.nx + sx;
        if (covered[static_cast<std::size_t>(start)]) continue;
        const ReachPose p = reach.solve(Reach::target(wall, m.x_min + sx * m.grid, m.y_min + sy * m.grid, standoff, roll),
                                        wall, reach.neutral(), nullptr, true);
        if (!p.ok) {
          if (reasons[static_cast<std::size_t>(start)].empty()) reasons[static_cast<std::size_t>(start)] = p.reason;
          continue;
        }
        Region region = flood(reach, wall, standoff, roll, m, start, p.q, reasons);
        AreaMap probe = m;
        probe.reachable.assign(n, 0);
        for (std::size_t i = 0; i < n; ++i) {
          if (region.q[i]) {
            probe.reachable[i] = 1;
            covered[i] = 1;
          }
        }
        const CellRect rect = maximal_rectangle(probe);
        if (rect.area() > best_area) {
          best_area = rect.area();
          best_rect = rect;
          best = std::move(region);
          m.roll = roll;
        }
      }
    }
  }
  if (best.q.empty()) best.q.assign(n, std::nullopt);
  m.reachable.assign(n, 0);
  m.reasons = reasons;
  m.postures.assign(n, Eigen::VectorXd());
  for (std::size_t i = 0; i < n; ++i) {
    if (best.q[i]) m.postures[i] = *best.q[i];
    m.reachable[i] = best.q[i] ? 1 : 0;
    if (best.q[i]) m.reasons[i].clear();
    if (!best.q[i] && m.reasons[i].empty()) m.reasons[i] = "not connected to the reachable band";
  }
  if (best.count == 0) {
    std::map<std::string, int> why;
    for (const std::string& r : m.reasons) ++why[r];
    const auto top = std::max_element(why.begin(), why.end(), [](auto& a, auto& b) { return a.second < b.second; });
    throw FinishError(reach.model().where() + ": the " + reach.tool_name() + " reaches no point of the wall " +
                      std::to_string(m.wall_distance).substr(0, 4) + " m ahead (mostly: " + top->first + ")");
  }
  const CellRect r = best_rect;
  m.band = Rect{m.x_min + r.ix0 * m.grid, m.x_min + r.ix1 * m.grid, m.y_min + r.iy0 * m.grid, m.y_min + r.iy1 * m.grid};
  // Panels: the band's columns split into equal parts (cell boundaries shared by neighbours).
  const int cells = r.ix1 - r.ix0;
  for (int p = 0; p < params.panels; ++p) {
    const int a = r.ix0 + cells * p / params.panels;
    const int b = r.ix0 + cells * (p + 1) / params.panels;
    Area area;
    if (params.panels == 3) {
      area.id = p == 0 ? "left" : p == 1 ? "centre" : "right";
    } else if (params.panels == 1) {
      area.id = "centre";
    } else {
      area.id = "panel_" + std::to_string(p);
    }
    area.rect = Rect{m.x_min + a * m.grid, m.x_min + b * m.grid, m.band.y0, m.band.y1};
    m.areas.push_back(area);
  }
  m.areas.push_back(Area{"all", m.band});
  return m;
}

AreaMap working_areas(Reach& reach, Task task, double standoff, const AreaParams& params) {
  if (params.distances.empty()) throw FinishError("area parameters: no working distance to try");
  AreaParams coarse = params;
  coarse.grid = params.coarse_grid;
  double best_distance = params.distances.front();
  double best_area = -1.0;
  std::string last_error;
  for (const double d : params.distances) {
    try {
      const AreaMap m = compute_areas(reach, WallFrame::ahead(d, reach.standing_height()), task, standoff, coarse);
      const double a = m.band.width() * m.band.height();
      if (a > best_area) {
        best_area = a;
        best_distance = d;
      }
    } catch (const FinishError& e) {
      last_error = e.what();
    }
  }
  if (best_area < 0.0) throw FinishError(last_error);
  return compute_areas(reach, WallFrame::ahead(best_distance, reach.standing_height()), task, standoff, params);
}

Rect reshape(const Area& area, const Rect& rect) {
  if (!(rect.x1 > rect.x0) || !(rect.y1 > rect.y0)) {
    throw FinishError("reshaped rectangle " + rect.str() + " of area '" + area.id + "' has no positive size");
  }
  if (!area.rect.contains(rect, 1e-6)) {
    throw FinishError("reshaped rectangle " + rect.str() + " is not inside area '" + area.id + "' " + area.rect.str());
  }
  return rect;
}

}  // namespace concert::surface_finish
