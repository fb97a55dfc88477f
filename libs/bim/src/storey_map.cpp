#include "concert/bim/storey_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace concert::bim {

namespace {

/// A cell index from a (floored or ceiled) count of cells: a vertex far off the grid gives an
/// index far outside it, never an int conversion out of range (undefined behaviour).
int cell_index(double cells) {
  if (std::isnan(cells)) return std::numeric_limits<int>::min();
  return static_cast<int>(std::clamp(cells, -1e9, 1e9));
}


/// Touching is not overlapping: material exactly on a cell border marks one side only.
constexpr double kEps = 1e-7;

using Polygon = std::vector<Eigen::Vector3d>;

/// Sutherland-Hodgman: the part of a convex polygon with sign * (z - z0) >= 0.
Polygon clip_z(const Polygon& in, double z0, double sign) {
  Polygon out;
  const std::size_t n = in.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& a = in[i];
    const Eigen::Vector3d& b = in[(i + 1) % n];
    const double da = sign * (a.z() - z0);
    const double db = sign * (b.z() - z0);
    if (da >= 0) out.push_back(a);
    if ((da >= 0) != (db >= 0)) out.push_back(a + (b - a) * (da / (da - db)));
  }
  return out;
}

/// Separating-axis test of a convex polygon (projected to xy; may be a segment or a point)
/// against the axis-aligned box [lo, hi].
bool overlaps(const Polygon& poly, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  const std::size_t n = poly.size();
  const Eigen::Vector2d c = (lo + hi) / 2;
  const Eigen::Vector2d half = (hi - lo) / 2;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d e = (poly[(i + 1) % n] - poly[i]).head<2>();
    if (e.norm() < 1e-12) continue;
    const Eigen::Vector2d axis(-e.y(), e.x());
    double pmin = std::numeric_limits<double>::infinity();
    double pmax = -pmin;
    for (const auto& p : poly) {
      const double d = axis.dot(p.head<2>());
      pmin = std::min(pmin, d);
      pmax = std::max(pmax, d);
    }
    const double r = std::abs(axis.x()) * half.x() + std::abs(axis.y()) * half.y();
    const double cd = axis.dot(c);
    if (pmax < cd - r || pmin > cd + r) return false;
  }
  return true;
}

/// Marks cells of a local window [c0, c1] x [r0, r1] of `grid`.
class Mask {
 public:
  Mask(const OccupancyGrid& grid, int c0, int r0, int c1, int r1)
      : grid_(grid),
        c0_(c0),
        r0_(r0),
        w_(c1 - c0 + 1),
        h_(r1 - r0 + 1),
        bits_(static_cast<std::size_t>(std::max(0, w_)) * static_cast<std::size_t>(std::max(0, h_)),
              false) {}
  void set(int col, int row) {
    if (col < c0_ || row < r0_ || col >= c0_ + w_ || row >= r0_ + h_) return;
    bits_[static_cast<std::size_t>(row - r0_) * static_cast<std::size_t>(w_) +
          static_cast<std::size_t>(col - c0_)] = true;
  }
  [[nodiscard]] std::vector<Eigen::Vector2i> cells() const {
    std::vector<Eigen::Vector2i> out;
    for (int r = 0; r < h_; ++r) {
      for (int c = 0; c < w_; ++c) {
        if (bits_[static_cast<std::size_t>(r) * static_cast<std::size_t>(w_) +
                  static_cast<std::size_t>(c)]) {
          out.emplace_back(c0_ + c, r0_ + r);
        }
      }
    }
    return out;
  }
  [[nodiscard]] int c0() const { return c0_; }
  [[nodiscard]] int r0() const { return r0_; }
  [[nodiscard]] int c1() const { return c0_ + w_ - 1; }
  [[nodiscard]] int r1() const { return r0_ + h_ - 1; }
  [[nodiscard]] const OccupancyGrid& grid() const { return grid_; }

 private:
  const OccupancyGrid& grid_;
  int c0_, r0_, w_, h_;
  std::vector<bool> bits_;
};

/// The element's triangles clipped to the band, each marking every cell it touches.
void mark_surface(const Mesh& mesh, double z_min, double z_max, Mask& mask) {
  const OccupancyGrid& g = mask.grid();
  for (const auto& t : mesh.triangles) {
    Polygon p{mesh.vertices[static_cast<std::size_t>(t[0])],
              mesh.vertices[static_cast<std::size_t>(t[1])],
              mesh.vertices[static_cast<std::size_t>(t[2])]};
    p = clip_z(p, z_min, 1.0);
    if (p.empty()) continue;
    p = clip_z(p, z_max, -1.0);
    if (p.empty()) continue;
    Eigen::Vector2d lo = p[0].head<2>();
    Eigen::Vector2d hi = lo;
    for (const auto& v : p) {
      lo = lo.cwiseMin(v.head<2>());
      hi = hi.cwiseMax(v.head<2>());
    }
    const int ca = std::max(
        mask.c0(), cell_index(std::floor((lo.x() - g.origin.x() + kEps) / g.resolution)));
    const int cb = std::min(
        mask.c1(), cell_index(std::floor((hi.x() - g.origin.x() - kEps) / g.resolution)));
    const int ra = std::max(
        mask.r0(), cell_index(std::floor((lo.y() - g.origin.y() + kEps) / g.resolution)));
    const int rb = std::min(
        mask.r1(), cell_index(std::floor((hi.y() - g.origin.y() - kEps) / g.resolution)));
    for (int r = ra; r <= rb; ++r) {
      for (int c = ca; c <= cb; ++c) {
        const Eigen::Vector2d cell_lo =
            g.origin + g.resolution * Eigen::Vector2d(c, r) + Eigen::Vector2d::Constant(kEps);
        const Eigen::Vector2d cell_hi = g.origin + g.resolution * Eigen::Vector2d(c + 1, r + 1) -
                                        Eigen::Vector2d::Constant(kEps);
        if (overlaps(p, cell_lo, cell_hi)) mask.set(c, r);
      }
    }
  }
}

/// The inside of the element's horizontal cross-section at height z (even-odd rule along each
/// row through the cell centres; a row with an odd number of crossings, where the mesh is not
/// closed, is left alone).
void mark_section(const Mesh& mesh, double z, Mask& mask) {
  const OccupancyGrid& g = mask.grid();
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> segments;
  for (const auto& t : mesh.triangles) {
    std::array<Eigen::Vector2d, 2> ends;
    int n = 0;
    for (int k = 0; k < 3 && n < 2; ++k) {
      const Eigen::Vector3d& a = mesh.vertices[static_cast<std::size_t>(t[k])];
      const Eigen::Vector3d& b = mesh.vertices[static_cast<std::size_t>(t[(k + 1) % 3])];
      if ((a.z() >= z) != (b.z() >= z)) {
        ends[static_cast<std::size_t>(n++)] =
            (a + (b - a) * ((z - a.z()) / (b.z() - a.z()))).head<2>();
      }
    }
    if (n == 2) segments.emplace_back(ends[0], ends[1]);
  }
  if (segments.empty()) return;
  std::vector<double> xs;
  for (int r = mask.r0(); r <= mask.r1(); ++r) {
    const double y = g.origin.y() + (r + 0.5) * g.resolution;
    xs.clear();
    for (const auto& [a, b] : segments) {
      if ((a.y() <= y) != (b.y() <= y))
        xs.push_back(a.x() + (b.x() - a.x()) * (y - a.y()) / (b.y() - a.y()));
    }
    if (xs.size() < 2 || xs.size() % 2 != 0) continue;
    std::sort(xs.begin(), xs.end());
    for (std::size_t i = 0; i + 1 < xs.size(); i += 2) {
      const int ca = std::max(
          mask.c0(), cell_index(std::ceil((xs[i] - g.origin.x()) / g.resolution - 0.5)));
      const int cb = std::min(
          mask.c1(), cell_index(std::floor((xs[i + 1] - g.origin.x()) / g.resolution - 0.5)));
      for (int c = ca; c <= cb; ++c) mask.set(c, r);
    }
  }
}

}  // namespace

std::vector<Eigen::Vector2i> element_cells(const Element& element, const OccupancyGrid& grid,
                                           double z_min, double z_max) {
  if (element.mesh.triangles.empty() || element.bounds.isEmpty()) return {};
  if (element.bounds.max().z() < z_min || element.bounds.min().z() > z_max) return {};
  const Eigen::Vector2i lo = grid.cell_of(element.bounds.min().head<2>());
  const Eigen::Vector2i hi = grid.cell_of(element.bounds.max().head<2>());
  const int c0 = std::max(0, lo.x());
  const int r0 = std::max(0, lo.y());
  const int c1 = std::min(grid.width - 1, hi.x());
  const int r1 = std::min(grid.height - 1, hi.y());
  if (c0 > c1 || r0 > r1) return {};
  Mask mask(grid, c0, r0, c1, r1);
  mark_surface(element.mesh, z_min, z_max, mask);
  const double step = grid.resolution / 2;
  const int slices = std::max(2, static_cast<int>(std::ceil((z_max - z_min) / step)) + 1);
  for (int k = 0; k < slices; ++k) {
    const double z = z_min + kEps + (z_max - z_min - 2 * kEps) * k / (slices - 1);
    if (z < element.bounds.min().z() || z > element.bounds.max().z()) continue;
    mark_section(element.mesh, z, mask);
  }
  return mask.cells();
}

OccupancyGrid storey_map(const BimModel& model, const Storey& storey, const SliceParams& params) {
  std::ostringstream where;
  where << "storey '" << storey.name << "' of " << model.source;
  if (!(params.band_max > params.band_min) || !std::isfinite(params.band_min) ||
      !std::isfinite(params.band_max)) {
    throw BimError(where.str() + ": slice band " + std::to_string(params.band_min) + " .. " +
                   std::to_string(params.band_max) +
                   " m: the upper edge must be above the lower one");
  }
  if (!(params.resolution > 0) || !std::isfinite(params.resolution)) {
    throw BimError(where.str() + ": resolution " + std::to_string(params.resolution) +
                   " m: must be > 0");
  }
  if (!(params.margin >= 0)) throw BimError(where.str() + ": margin must be >= 0 m");
  Eigen::AlignedBox3d extent;
  for (const Element* e : model.elements_of(storey)) {
    if (!e->bounds.isEmpty()) extent.extend(e->bounds);
  }
  if (extent.isEmpty()) throw BimError(where.str() + ": no element with geometry on this storey");
  const double res = params.resolution;
  const Eigen::Vector2d lo = ((extent.min().head<2>().array() - params.margin) / res).floor() * res;
  const Eigen::Vector2d hi = extent.max().head<2>().array() + params.margin;
  const Eigen::Vector2d cells = ((hi - lo) / res).array().ceil();
  if (!(cells.x() >= 1 && cells.y() >= 1 && cells.x() * cells.y() <= 2e8)) {
    std::ostringstream size;
    size << cells.x() << " x " << cells.y();
    throw BimError(where.str() + ": " + size.str() + " cells at " + std::to_string(res) +
                   " m: a map needs 1 to 2e8 cells (use a coarser resolution, or a margin)");
  }
  OccupancyGrid grid = OccupancyGrid::filled(
      static_cast<int>(cells.x()), static_cast<int>(cells.y()), res, lo, OccupancyGrid::kFree);
  const double z_min = storey.elevation + params.band_min;
  const double z_max = storey.elevation + params.band_max;
  for (const auto& e : model.elements) {
    if (!is_obstacle(e.category)) continue;
    for (const auto& c : element_cells(e, grid, z_min, z_max))
      grid.at(c.x(), c.y()) = OccupancyGrid::kOccupied;
  }
  return grid;
}

}  // namespace concert::bim
