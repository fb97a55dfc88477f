#include "planner/environment.hpp"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace concert::planner {
namespace {

constexpr double kFieldMargin = 0.6;       // [m] grid beyond the occupied extent
constexpr std::size_t kMaxFieldCells = 16'000'000;  // coarser grid beyond this (64 MB of floats)

// Exact 1-D squared distance transform (Felzenszwalb and Huttenlocher 2012) of f along a line
// of n samples with stride `stride`, in place; `v`, `z`, `g` are scratch.
void transform_line(float* f, long n, long stride, std::vector<long>& v, std::vector<double>& z, std::vector<double>& g) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  g.resize(static_cast<std::size_t>(n));
  v.resize(static_cast<std::size_t>(n));
  z.resize(static_cast<std::size_t>(n) + 1);
  for (long q = 0; q < n; ++q) g[static_cast<std::size_t>(q)] = f[q * stride];
  long k = -1;
  for (long q = 0; q < n; ++q) {
    const double gq = g[static_cast<std::size_t>(q)];
    if (gq == inf) continue;
    double s = -inf;
    while (k >= 0) {
      const long p = v[static_cast<std::size_t>(k)];
      s = ((gq + static_cast<double>(q * q)) - (g[static_cast<std::size_t>(p)] + static_cast<double>(p * p))) / (2.0 * static_cast<double>(q - p));
      if (s > z[static_cast<std::size_t>(k)]) break;
      --k;
    }
    ++k;
    v[static_cast<std::size_t>(k)] = q;
    z[static_cast<std::size_t>(k)] = k == 0 ? -inf : s;
    z[static_cast<std::size_t>(k) + 1] = inf;
  }
  if (k < 0) return;  // nothing finite on this line
  long j = 0;
  for (long q = 0; q < n; ++q) {
    while (z[static_cast<std::size_t>(j) + 1] < static_cast<double>(q)) ++j;
    const long p = v[static_cast<std::size_t>(j)];
    f[q * stride] = static_cast<float>(static_cast<double>((q - p) * (q - p)) + g[static_cast<std::size_t>(p)]);
  }
}

// Squared distance (in cells) of every cell to the nearest cell where `seed` is 0.
void squared_distances(std::vector<float>& f, long nx, long ny, long nz) {
  std::vector<long> v;
  std::vector<double> z, g;
  for (long k = 0; k < nz; ++k) {
    for (long j = 0; j < ny; ++j) transform_line(&f[static_cast<std::size_t>((k * ny + j) * nx)], nx, 1, v, z, g);
  }
  for (long k = 0; k < nz; ++k) {
    for (long i = 0; i < nx; ++i) transform_line(&f[static_cast<std::size_t>(k * ny * nx + i)], ny, nx, v, z, g);
  }
  for (long j = 0; j < ny; ++j) {
    for (long i = 0; i < nx; ++i) transform_line(&f[static_cast<std::size_t>(j * nx + i)], nz, nx * ny, v, z, g);
  }
}

}  // namespace

DistanceField::DistanceField(const octomap::OcTree& tree, double margin) : margin_(margin) {
  resolution_ = tree.getResolution();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  std::vector<std::pair<Eigen::Vector3d, double>> boxes;  // occupied leaves: centre, size
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const Eigen::Vector3d c(it.getX(), it.getY(), it.getZ());
    const double size = it.getSize();
    boxes.emplace_back(c, size);
    lo = lo.cwiseMin(c - Eigen::Vector3d::Constant(0.5 * size));
    hi = hi.cwiseMax(c + Eigen::Vector3d::Constant(0.5 * size));
  }
  if (boxes.empty()) return;  // empty map: every point reads as margin
  lo -= Eigen::Vector3d::Constant(margin);
  hi += Eigen::Vector3d::Constant(margin);
  // Cells aligned with the map's voxels; coarser when the extent is huge.
  auto counts = [&] {
    return Eigen::Vector3d(std::ceil((hi.x() - lo.x()) / resolution_), std::ceil((hi.y() - lo.y()) / resolution_),
                           std::ceil((hi.z() - lo.z()) / resolution_));
  };
  while (counts().prod() > static_cast<double>(kMaxFieldCells)) resolution_ *= 2.0;
  lo = (lo / resolution_).array().floor().matrix() * resolution_;
  const Eigen::Vector3d n = counts();
  nx_ = static_cast<long>(n.x());
  ny_ = static_cast<long>(n.y());
  nz_ = static_cast<long>(n.z());
  origin_ = lo + Eigen::Vector3d::Constant(0.5 * resolution_);
  const auto cells = static_cast<std::size_t>(nx_ * ny_ * nz_);
  std::vector<char> occupied(cells, 0);
  for (const auto& [c, size] : boxes) {
    // Every grid cell whose centre lies in the leaf's cube.
    const Eigen::Vector3d a = (c - Eigen::Vector3d::Constant(0.5 * size) - origin_) / resolution_;
    const Eigen::Vector3d b = (c + Eigen::Vector3d::Constant(0.5 * size) - origin_) / resolution_;
    const long i0 = std::max(0L, static_cast<long>(std::ceil(a.x() - 1e-9))), i1 = std::min(nx_ - 1, static_cast<long>(std::floor(b.x() - 1e-9)));
    const long j0 = std::max(0L, static_cast<long>(std::ceil(a.y() - 1e-9))), j1 = std::min(ny_ - 1, static_cast<long>(std::floor(b.y() - 1e-9)));
    const long k0 = std::max(0L, static_cast<long>(std::ceil(a.z() - 1e-9))), k1 = std::min(nz_ - 1, static_cast<long>(std::floor(b.z() - 1e-9)));
    for (long k = k0; k <= k1; ++k) {
      for (long j = j0; j <= j1; ++j) {
        for (long i = i0; i <= i1; ++i) occupied[static_cast<std::size_t>((k * ny_ + j) * nx_ + i)] = 1;
      }
    }
  }
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> outside(cells), inside(cells);
  for (std::size_t c = 0; c < cells; ++c) {
    outside[c] = occupied[c] != 0 ? 0.0F : inf;
    inside[c] = occupied[c] != 0 ? inf : 0.0F;
  }
  squared_distances(outside, nx_, ny_, nz_);
  squared_distances(inside, nx_, ny_, nz_);
  values_.resize(cells);
  const double half_diagonal = 0.5 * std::sqrt(3.0) * resolution_;
  for (std::size_t c = 0; c < cells; ++c) {
    const double d = occupied[c] != 0 ? -std::sqrt(static_cast<double>(inside[c])) * resolution_
                                      : std::sqrt(static_cast<double>(outside[c])) * resolution_ - half_diagonal;
    values_[c] = static_cast<float>(d);
  }
}

double DistanceField::at(long i, long j, long k) const {
  return values_[static_cast<std::size_t>((k * ny_ + j) * nx_ + i)];
}

double DistanceField::distance(const Eigen::Vector3d& p) const {
  if (values_.empty()) return margin_;
  const Eigen::Vector3d u = (p - origin_) / resolution_;
  const Eigen::Vector3d fl = u.array().floor();
  const long i = static_cast<long>(fl.x()), j = static_cast<long>(fl.y()), k = static_cast<long>(fl.z());
  if (i < 0 || j < 0 || k < 0 || i + 1 >= nx_ || j + 1 >= ny_ || k + 1 >= nz_) return margin_;
  const Eigen::Vector3d t = u - fl;
  double out = 0.0;
  for (int c = 0; c < 8; ++c) {
    const int di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
    const double w = (di != 0 ? t.x() : 1.0 - t.x()) * (dj != 0 ? t.y() : 1.0 - t.y()) * (dk != 0 ? t.z() : 1.0 - t.z());
    out += w * at(i + di, j + dj, k + dk);
  }
  return std::min(out, margin_);
}

struct Environment::LazyField {
  std::once_flag once;
  std::shared_ptr<const DistanceField> field;
};

std::shared_ptr<const DistanceField> Environment::distance_field() const {
  LazyField& lazy = *field_;
  std::call_once(lazy.once, [&] { lazy.field = std::make_shared<DistanceField>(*tree_, kFieldMargin); });
  return lazy.field;
}

Environment::Environment(double resolution) : resolution_(resolution) {
  if (!(resolution > 0.0)) throw PlannerError("environment: octomap resolution must be > 0, got " + std::to_string(resolution));
  tree_ = std::make_shared<octomap::OcTree>(resolution);
  field_ = std::make_shared<LazyField>();
}

std::shared_ptr<octomap::OcTree> Environment::mutable_copy() const { return std::make_shared<octomap::OcTree>(*tree_); }

void Environment::add_world(const World& world) {
  auto tree = mutable_copy();
  const double r = resolution_;
  // Fills the voxels of a bounding region whose centres pass `inside`.
  auto fill = [&](const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, auto inside) {
    for (double x = std::floor(lo.x() / r) * r + 0.5 * r; x < hi.x(); x += r) {
      for (double y = std::floor(lo.y() / r) * r + 0.5 * r; y < hi.y(); y += r) {
        for (double z = std::floor(lo.z() / r) * r + 0.5 * r; z < hi.z(); z += r) {
          if (inside(Eigen::Vector3d(x, y, z))) tree->updateNode(octomap::point3d(float(x), float(y), float(z)), true, true);
        }
      }
    }
  };
  for (std::size_t i = 0; i < world.boxes.size(); ++i) {
    const WorldBox& b = world.boxes[i];
    if ((b.size.array() <= 0.0).any()) {
      throw PlannerError("world: box " + std::to_string(i) + " '" + b.name + "': size must be positive in x, y and z");
    }
    const Eigen::Matrix3d rot = Eigen::AngleAxisd(b.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d half = 0.5 * b.size;
    const Eigen::Vector3d ext = rot.cwiseAbs() * half;
    // Half a voxel of slack so a thin wall still fills at least one voxel layer.
    const Eigen::Vector3d grown = half + Eigen::Vector3d::Constant(0.5 * r);
    fill(b.position - ext - Eigen::Vector3d::Constant(r), b.position + ext + Eigen::Vector3d::Constant(r), [&](const Eigen::Vector3d& p) {
      const Eigen::Vector3d local = rot.transpose() * (p - b.position);
      return (local.cwiseAbs().array() <= grown.array()).all();
    });
  }
  for (std::size_t i = 0; i < world.cylinders.size(); ++i) {
    const WorldCylinder& c = world.cylinders[i];
    if (!(c.radius > 0.0) || !(c.height > 0.0)) {
      throw PlannerError("world: cylinder " + std::to_string(i) + " '" + c.name + "': radius and height must be positive");
    }
    const Eigen::Vector3d ext(c.radius + r, c.radius + r, 0.5 * c.height + r);
    fill(c.position - ext, c.position + ext, [&](const Eigen::Vector3d& p) {
      return (p - c.position).head<2>().norm() <= c.radius + 0.5 * r && std::abs(p.z() - c.position.z()) <= 0.5 * (c.height + r);
    });
  }
  tree->updateInnerOccupancy();
  tree->prune();
  tree_ = tree;
  field_ = std::make_shared<LazyField>();
}

void Environment::insert_point_cloud(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& origin, double max_range) {
  octomap::Pointcloud cloud;
  cloud.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) throw PlannerError("point cloud: point " + std::to_string(i) + " is not finite");
    cloud.push_back(float(points[i].x()), float(points[i].y()), float(points[i].z()));
  }
  if (!origin.allFinite()) throw PlannerError("point cloud: sensor origin is not finite");
  auto tree = mutable_copy();
  tree->insertPointCloud(cloud, octomap::point3d(float(origin.x()), float(origin.y()), float(origin.z())), max_range);
  tree->updateInnerOccupancy();
  tree->prune();
  tree_ = tree;
  field_ = std::make_shared<LazyField>();
}

void Environment::insert_rays(const Eigen::Vector3d& origin, const std::vector<Eigen::Vector3d>& hits,
                              const std::vector<Eigen::Vector3d>& clears) {
  insert_rays(std::vector<RayBundle>{RayBundle{origin, hits, clears}});
}

void Environment::insert_rays(const std::vector<RayBundle>& bundles) {
  for (std::size_t b = 0; b < bundles.size(); ++b) {
    const RayBundle& bundle = bundles[b];
    const std::string which = bundles.size() > 1 ? "rays of bundle " + std::to_string(b) : "rays";
    if (!bundle.origin.allFinite()) throw PlannerError(which + ": sensor origin is not finite");
    for (std::size_t i = 0; i < bundle.hits.size(); ++i) {
      if (!bundle.hits[i].allFinite()) throw PlannerError(which + ": hit " + std::to_string(i) + " is not finite");
    }
    for (std::size_t i = 0; i < bundle.clears.size(); ++i) {
      if (!bundle.clears[i].allFinite()) throw PlannerError(which + ": cleared end " + std::to_string(i) + " is not finite");
    }
  }
  auto tree = mutable_copy();
  octomap::KeySet free_cells, occupied_cells;
  octomap::KeyRay ray;
  for (const RayBundle& bundle : bundles) {
    const octomap::point3d o(float(bundle.origin.x()), float(bundle.origin.y()), float(bundle.origin.z()));
    auto pass = [&](const Eigen::Vector3d& end) {
      const octomap::point3d e(float(end.x()), float(end.y()), float(end.z()));
      if (tree->computeRayKeys(o, e, ray)) free_cells.insert(ray.begin(), ray.end());
      return e;
    };
    for (const Eigen::Vector3d& h : bundle.hits) {
      octomap::OcTreeKey key;
      if (tree->coordToKeyChecked(pass(h), key)) occupied_cells.insert(key);
    }
    for (const Eigen::Vector3d& c : bundle.clears) {
      octomap::OcTreeKey key;
      if (tree->coordToKeyChecked(pass(c), key)) free_cells.insert(key);
    }
  }
  for (const octomap::OcTreeKey& key : free_cells) {
    if (occupied_cells.count(key) == 0) tree->updateNode(key, false, true);
  }
  for (const octomap::OcTreeKey& key : occupied_cells) tree->updateNode(key, true, true);
  tree->updateInnerOccupancy();
  tree->prune();
  tree_ = tree;
  field_ = std::make_shared<LazyField>();
}

void Environment::add_occupied(const Environment& other) {
  if (other.resolution_ != resolution_) {
    throw PlannerError("environment: cannot add a map of resolution " + std::to_string(other.resolution_) +
                       " m to one of " + std::to_string(resolution_) + " m");
  }
  auto tree = mutable_copy();
  const octomap::OcTree& src = *other.tree_;
  for (auto it = src.begin_leafs(); it != src.end_leafs(); ++it) {
    if (!src.isNodeOccupied(*it)) continue;
    // A pruned leaf covers several cells: mark each of them.
    const double size = it.getSize();
    const int n = std::max(1, static_cast<int>(std::lround(size / resolution_)));
    const Eigen::Vector3d lo = Eigen::Vector3d(it.getX(), it.getY(), it.getZ()) - Eigen::Vector3d::Constant(0.5 * size - 0.5 * resolution_);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n; ++k) {
          const Eigen::Vector3d c = lo + resolution_ * Eigen::Vector3d(i, j, k);
          tree->updateNode(octomap::point3d(float(c.x()), float(c.y()), float(c.z())), true, true);
        }
      }
    }
  }
  tree->updateInnerOccupancy();
  tree->prune();
  tree_ = tree;
  field_ = std::make_shared<LazyField>();
}

std::size_t Environment::occupied_cells() const {
  std::size_t n = 0;
  for (auto it = tree_->begin_leafs(); it != tree_->end_leafs(); ++it) {
    if (tree_->isNodeOccupied(*it)) n += 1;
  }
  return n;
}

bool Environment::occupied(const Eigen::Vector3d& p) const {
  const octomap::OcTreeNode* node = tree_->search(p.x(), p.y(), p.z());
  return node != nullptr && tree_->isNodeOccupied(node);
}

}  // namespace concert::planner
