#include "concert/bim/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

namespace concert::bim {

namespace {

using Json = nlohmann::ordered_json;

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

/// Andrew's monotone chain: the convex hull, counter-clockwise.
std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> pts) {
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  std::vector<Eigen::Vector2d> hull(2 * pts.size());
  std::size_t k = 0;
  for (const auto& p : pts) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0) --k;
    hull[k++] = p;
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);
  return hull;
}

Json vec(const Eigen::Vector2d& v) { return Json::array({v.x(), v.y()}); }

Json box_json(const OrientedBox2& b) {
  Json corners = Json::array();
  for (const auto& c : b.corners()) corners.push_back(vec(c));
  return Json{
      {"center", vec(b.center)}, {"size", vec(2 * b.half)}, {"yaw", b.yaw}, {"corners", corners}};
}

}  // namespace

std::array<Eigen::Vector2d, 4> OrientedBox2::corners() const {
  const Eigen::Vector2d u(std::cos(yaw), std::sin(yaw));
  const Eigen::Vector2d v(-u.y(), u.x());
  return {center - half.x() * u - half.y() * v, center + half.x() * u - half.y() * v,
          center + half.x() * u + half.y() * v, center - half.x() * u + half.y() * v};
}

OrientedBox2 footprint(const Element& element) {
  if (element.mesh.vertices.empty()) {
    throw BimError(element.ifc_type + " '" + element.global_id + "' has no geometry");
  }
  std::vector<Eigen::Vector2d> pts;
  pts.reserve(element.mesh.vertices.size());
  for (const auto& v : element.mesh.vertices) pts.push_back(v.head<2>());
  const auto hull = convex_hull(pts);
  OrientedBox2 best;
  double best_area = std::numeric_limits<double>::infinity();
  auto try_direction = [&](const Eigen::Vector2d& dir) {
    const Eigen::Vector2d u = dir.normalized();
    const Eigen::Vector2d v(-u.y(), u.x());
    double umin = std::numeric_limits<double>::infinity(), umax = -umin, vmin = umin, vmax = -umin;
    for (const auto& p : hull) {
      umin = std::min(umin, u.dot(p));
      umax = std::max(umax, u.dot(p));
      vmin = std::min(vmin, v.dot(p));
      vmax = std::max(vmax, v.dot(p));
    }
    const double area = (umax - umin) * (vmax - vmin);
    if (area < best_area - 1e-12) {
      best_area = area;
      OrientedBox2 b;
      b.center = u * (umin + umax) / 2 + v * (vmin + vmax) / 2;
      b.half = {(umax - umin) / 2, (vmax - vmin) / 2};
      b.yaw = std::atan2(u.y(), u.x());
      if (b.half.y() > b.half.x()) {  // the box's x along its long side
        std::swap(b.half.x(), b.half.y());
        b.yaw += M_PI / 2;
      }
      best = b;
    }
  };
  try_direction(Eigen::Vector2d::UnitX());
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d e = hull[(i + 1) % hull.size()] - hull[i];
    if (e.norm() > 1e-9) try_direction(e);
  }
  best.yaw = std::remainder(best.yaw, 2 * M_PI);
  return best;
}

WallGeometry wall_geometry(const Element& wall) {
  if (wall.category != Category::kWall) {
    throw BimError("element '" + wall.global_id + "' is an " + wall.ifc_type + ", not a wall");
  }
  const OrientedBox2 box = footprint(wall);
  Eigen::Vector2d d(std::cos(box.yaw), std::sin(box.yaw));
  if (wall.placement_x && d.dot(wall.placement_x->head<2>()) < 0) d = -d;
  WallGeometry g;
  g.start = box.center - box.half.x() * d;
  g.end = box.center + box.half.x() * d;
  g.thickness = 2 * box.half.y();
  g.z_min = wall.bounds.min().z();
  g.z_max = wall.bounds.max().z();
  const Eigen::Vector2d left(-d.y(), d.x());
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector2d n = k == 0 ? left : -left;
    g.faces[static_cast<std::size_t>(k)] = {n, g.start + n * box.half.y(),
                                            g.end + n * box.half.y()};
  }
  return g;
}

std::string geometry_json(const BimModel& model, const Storey& storey) {
  Json elements = Json::array();
  for (const Element* e : model.elements_of(storey)) {
    const Category c = e->category;
    if (c != Category::kWall && c != Category::kDoor && c != Category::kWindow &&
        c != Category::kColumn && c != Category::kSlab) {
      continue;
    }
    Json j{{"global_id", e->global_id},
           {"type", e->ifc_type},
           {"category", to_string(c)},
           {"name", e->name}};
    if (e->mesh.vertices.empty()) {
      j["footprint"] = nullptr;
      j["z"] = nullptr;
    } else {
      j["footprint"] = box_json(footprint(*e));
      j["z"] = Json::array({e->bounds.min().z(), e->bounds.max().z()});
    }
    if (c == Category::kDoor || c == Category::kWindow) {
      j["host"] = e->host.empty() ? Json(nullptr) : Json(e->host);
    }
    if (c == Category::kWall && !e->mesh.vertices.empty()) {
      const WallGeometry w = wall_geometry(*e);
      Json faces = Json::array();
      for (const auto& f : w.faces) {
        faces.push_back(
            Json{{"normal", vec(f.normal)}, {"start", vec(f.start)}, {"end", vec(f.end)}});
      }
      j["axis"] = Json{{"start", vec(w.start)}, {"end", vec(w.end)}, {"length", w.length()}};
      j["thickness"] = w.thickness;
      j["faces"] = faces;
    }
    elements.push_back(std::move(j));
  }
  const Json out{{"format", "concert-bim-geometry"},
                 {"version", 1},
                 {"source", model.source},
                 {"frame", "IFC world frame: x y z [m], z up; map.yaml shares x y"},
                 {"storey", Json{{"name", storey.name},
                                 {"global_id", storey.global_id},
                                 {"elevation", storey.elevation}}},
                 {"elements", elements}};
  return out.dump(1);
}

}  // namespace concert::bim
