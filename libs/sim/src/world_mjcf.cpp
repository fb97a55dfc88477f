#include "world_mjcf.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "concert/world/aruco.hpp"
#include "concert/world/geometry.hpp"
#include "mjcf_text.hpp"

namespace concert::sim {

using mjcf::num;
using mjcf::vec;
using world::Face;
using world::Mark;
using world::Surface;
using world::WorldError;
using world::WorldShape;

namespace {

// Matte (no specular highlight) so that black stays black and white light grey under MuJoCo's
// headlight: good contrast for cameras.
constexpr const char* kMatte = "concert_world_matte";
constexpr const char* kWallRgba = "0.5 0.5 0.5 1";
constexpr const char* kPlasterRgba = "0.85 0.83 0.78 1";
constexpr const char* kBlackRgba = "0 0 0 1";
constexpr const char* kWhiteRgba = "1 1 1 1";
// ArUco white cells stand this much proud of the black square, so no two faces are coplanar
// (no z-fighting in the renderer) [m].
constexpr double kCellRelief = 0.0001;

std::string pose(const Eigen::Vector3d& p, const Eigen::Matrix3d& r) {
  const Eigen::Quaterniond q(r);
  return "pos=\"" + vec(p.x(), p.y(), p.z()) + "\" quat=\"" + num(q.w()) + " " +
         vec(q.x(), q.y(), q.z()) + "\"";
}

std::string friction(double f) { return "friction=\"" + num(f) + " 0.005 0.0001\""; }

struct HfieldGrid {
  int nrow{0};  // along z (up)
  int ncol{0};  // along u
  double top{0.0};
};

HfieldGrid grid(const Surface& s) {
  double highest = 0.0;
  for (const auto& b : s.bumps) {
    highest = std::max(highest, b.height);  // bumps do not overlap (validate_world)
  }
  return {static_cast<int>(std::lround(s.size.y() / s.resolution)) + 1,
          static_cast<int>(std::lround(s.size.x() / s.resolution)) + 1, s.thickness + highest};
}

/// The geom of a world shape, at the origin of its body (moving) or at its place (static).
void shape_geom(std::ostringstream& xml, const WorldShape& s, bool in_place, const char* rgba) {
  xml << "<geom name=\"" << s.name << "\" ";
  if (s.type == WorldShape::Type::kBox) {
    xml << "type=\"box\" size=\"" << vec(s.size.x() / 2, s.size.y() / 2, s.size.z() / 2) << "\"";
  } else {
    xml << "type=\"cylinder\" size=\"" << num(s.size.x()) << " " << num(s.size.z() / 2) << "\"";
  }
  xml << " group=\"0\"";
  if (in_place) {
    xml << " pos=\"" << vec(s.position.x(), s.position.y(), s.position.z()) << "\" euler=\"0 0 "
        << num(s.yaw) << "\"";
  }
  if (rgba != nullptr) {
    xml << " rgba=\"" << rgba << "\"";
  }
  xml << " contype=\"0\" conaffinity=\"1\" " << friction(s.friction) << "/>\n";
}

/// A visual box of a mark: half extents (hx, hy) in the mark's plane, from `back` to `front` in
/// front of the face [m]; (cx, cy) is its centre in the marker's upright frame.
void mark_box(std::ostringstream& xml, const std::string& name, const Eigen::Isometry3d& face,
              const Eigen::Vector2d& centre, double angle, double cx, double cy, double hx,
              double hy, double back, double front, const char* rgba) {
  const Eigen::Vector2d c = centre + Eigen::Rotation2Dd(angle) * Eigen::Vector2d(cx, cy);
  const Eigen::Matrix3d r =
      face.linear() * Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  xml << "<geom name=\"" << name << "\" type=\"box\" group=\"0\" size=\""
      << vec(hx, hy, 0.5 * (front - back)) << "\" "
      << pose(face * Eigen::Vector3d(c.x(), c.y(), 0.5 * (front + back)), r)
      << " contype=\"0\" conaffinity=\"0\" material=\"" << kMatte << "\" rgba=\"" << rgba
      << "\"/>\n";
}

void mark_geoms(std::ostringstream& xml, const world::World& world, const Mark& m) {
  const WorldShape& wall = world::find_wall(world, m.wall);
  const Eigen::Isometry3d face = world::face_frame(wall, m.face);
  // Face-frame coordinates of the mark's centre (the face frame's y is the height above the
  // face centre).
  const Eigen::Vector2d centre(m.at.x(), m.at.y() - wall.position.z());
  if (m.type == Mark::Type::kBlob) {
    const Eigen::Vector4d& c = m.rgba;
    xml << "<geom name=\"" << m.name << "\" type=\"cylinder\" group=\"0\" size=\""
        << num(0.5 * m.diameter) << " " << num(0.5 * world::kMarkStandoff) << "\" "
        << pose(face * Eigen::Vector3d(centre.x(), centre.y(), 0.5 * world::kMarkStandoff),
                face.linear())
        << " contype=\"0\" conaffinity=\"0\" material=\"" << kMatte << "\" rgba=\"" << num(c[0])
        << " " << vec(c[1], c[2], c[3]) << "\"/>\n";
    return;
  }
  // ArUco as geoms, not as a texture: exact cell edges at any distance (no texture filtering or
  // mip-mapping blur), nothing to put into MuJoCo's VFS, and any renderer (or ray) sees the
  // same geometry. A black square from the face to the front surface, then the white cells of
  // OpenCV's bit pattern (runs of a row merged into one box) just in front of it.
  const world::ArucoCells cells = world::aruco_cells(m.dictionary, m.id);
  const double cell = m.size / cells.side;
  const double half = 0.5 * m.size;
  mark_box(xml, m.name, face, centre, m.angle, 0.0, 0.0, half, half, 0.0, world::kMarkStandoff,
           kBlackRgba);
  for (int row = 0; row < cells.side; ++row) {
    for (int col = 0; col < cells.side;) {
      if (!cells.at(row, col)) {
        ++col;
        continue;
      }
      int end = col;
      while (end < cells.side && cells.at(row, end)) {
        ++end;
      }
      // Row 0 is the top, column 0 the left (u) of the upright marker seen from the front.
      const double cx = -half + cell * 0.5 * (col + end);
      const double cy = half - cell * (row + 0.5);
      mark_box(xml, m.name + "_white_" + std::to_string(row) + "_" + std::to_string(col), face,
               centre, m.angle, cx, cy, 0.5 * cell * (end - col), 0.5 * cell, world::kMarkStandoff,
               world::kMarkStandoff + kCellRelief, kWhiteRgba);
      col = end;
    }
  }
}

}  // namespace

WorldMjcf world_mjcf(const world::World& world) {
  std::ostringstream assets;
  std::ostringstream xml;
  if (world.floor) {
    xml << "<geom name=\"floor\" type=\"plane\" group=\"0\" size=\"100 100 0.1\" pos=\"0 0 "
        << num(world.floor_height) << "\" contype=\"0\" conaffinity=\"1\" "
        << friction(world.floor_friction) << "/>\n";
  }
  for (const auto& w : world.walls) {
    shape_geom(xml, w, true, kWallRgba);
  }
  for (const auto& o : world.obstacles) {
    if (!o.path) {
      shape_geom(xml, o, true, nullptr);
      continue;
    }
    xml << "<body name=\"" << o.name << "\" mocap=\"true\" pos=\""
        << vec(o.position.x(), o.position.y(), o.position.z()) << "\" euler=\"0 0 " << num(o.yaw)
        << "\">\n";
    shape_geom(xml, o, false, nullptr);
    xml << "</body>\n";
  }
  if (!world.marks.empty()) {
    assets << "<material name=\"" << kMatte
           << "\" specular=\"0\" shininess=\"0\" reflectance=\"0\"/>\n";
  }
  for (const auto& m : world.marks) {
    mark_geoms(xml, world, m);
  }
  for (const auto& s : world.surfaces) {
    // The height field's frame is the face frame moved to the panel's centre: x = u, y = up,
    // z = n; its zero level is the wall face, its base goes `thickness` into the wall.
    const WorldShape& wall = world::find_wall(world, s.wall);
    const HfieldGrid g = grid(s);
    assets << "<hfield name=\"" << s.name << "\" nrow=\"" << g.nrow << "\" ncol=\"" << g.ncol
           << "\" size=\"" << num(0.5 * s.size.x()) << " "
           << vec(0.5 * s.size.y(), g.top, s.thickness) << "\"/>\n";
    const Eigen::Isometry3d face = world::face_frame(wall, s.face);
    xml << "<geom name=\"" << s.name << "\" type=\"hfield\" hfield=\"" << s.name
        << "\" group=\"0\" " << pose(world::face_point(wall, s.face, s.at), face.linear())
        << " rgba=\"" << kPlasterRgba << "\" contype=\"0\" conaffinity=\"1\" "
        << friction(wall.friction) << "/>\n";
  }
  return {assets.str(), xml.str()};
}

void fill_world_hfields(const world::World& world, mjModel* model) {
  for (const auto& s : world.surfaces) {
    const int id = mj_name2id(model, mjOBJ_HFIELD, s.name.c_str());
    const HfieldGrid g = grid(s);
    if (id < 0 || model->hfield_nrow[id] != g.nrow || model->hfield_ncol[id] != g.ncol) {
      throw WorldError("sim: the MuJoCo model has no " + std::to_string(g.nrow) + " x " +
                       std::to_string(g.ncol) + " height field for surface '" + s.name + "'");
    }
    float* data = model->hfield_data + model->hfield_adr[id];
    const double top = model->hfield_size[4 * id + 2];
    // Row-major, row 0 at the bottom (y = -size[1]) and column 0 at the left (x = -size[0]).
    for (int r = 0; r < g.nrow; ++r) {
      const double z = s.at.y() - 0.5 * s.size.y() + s.size.y() * r / (g.nrow - 1);
      for (int c = 0; c < g.ncol; ++c) {
        const double u = s.at.x() - 0.5 * s.size.x() + s.size.x() * c / (g.ncol - 1);
        data[r * g.ncol + c] =
            static_cast<float>((s.thickness + world::surface_height(s, u, z)) / top);
      }
    }
  }
}

ObstacleMotion::ObstacleMotion(const world::World& world, const mjModel* model) {
  for (const auto& o : world.obstacles) {
    if (!o.path) {
      continue;
    }
    const int body = mj_name2id(model, mjOBJ_BODY, o.name.c_str());
    if (body < 0 || model->body_mocapid[body] < 0) {
      throw WorldError("sim: the MuJoCo model has no mocap body for moving obstacle '" + o.name +
                       "'");
    }
    movers_.push_back({o, model->body_mocapid[body]});
  }
}

void ObstacleMotion::apply(mjData* data, double t) const {
  for (const auto& m : movers_) {
    const Eigen::Vector3d p = world::obstacle_position(m.shape, t);
    std::copy_n(p.data(), 3, data->mocap_pos + 3 * m.mocap);
  }
}

}  // namespace concert::sim
