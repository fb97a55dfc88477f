#include "concert/bim/occupancy_grid.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace concert::bim {

namespace fs = std::filesystem;

OccupancyGrid OccupancyGrid::filled(int width, int height, double resolution,
                                    const Eigen::Vector2d& origin, std::int8_t fill) {
  if (width <= 0 || height <= 0) {
    throw MapError("occupancy grid: size " + std::to_string(width) + " x " +
                   std::to_string(height) + " cells: both must be > 0");
  }
  if (!(resolution > 0.0) || !std::isfinite(resolution)) {
    throw MapError("occupancy grid: resolution " + std::to_string(resolution) + " m: must be > 0");
  }
  OccupancyGrid g;
  g.width = width;
  g.height = height;
  g.resolution = resolution;
  g.origin = origin;
  g.cells.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), fill);
  return g;
}

Eigen::Vector2i OccupancyGrid::cell_of(const Eigen::Vector2d& p) const {
  // A point far off the grid (an element of another storey kilometres away, in georeferenced
  // coordinates) gets a cell far outside it, never an int conversion out of range (undefined).
  const auto index = [](double count) {
    if (std::isnan(count)) return std::numeric_limits<int>::min();
    return static_cast<int>(std::clamp(std::floor(count), -1e9, 1e9));
  };
  return {index((p.x() - origin.x()) / resolution), index((p.y() - origin.y()) / resolution)};
}

Eigen::Vector2d OccupancyGrid::center_of(int col, int row) const {
  return origin + resolution * Eigen::Vector2d(col + 0.5, row + 0.5);
}

bool OccupancyGrid::occupied(const Eigen::Vector2d& p) const {
  const Eigen::Vector2i c = cell_of(p);
  return !inside(c.x(), c.y()) || at(c.x(), c.y()) == kOccupied;
}

void save_map(const OccupancyGrid& grid, const std::string& dir, const std::string& stem) {
  if (grid.width <= 0 || grid.height <= 0 ||
      grid.cells.size() !=
          static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height)) {
    throw MapError("save_map: the grid's cells do not match its size " +
                   std::to_string(grid.width) + " x " + std::to_string(grid.height));
  }
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw MapError("save_map: cannot create '" + dir + "': " + ec.message());
  const fs::path pgm = fs::path(dir) / (stem + ".pgm");
  {
    std::ofstream out(pgm, std::ios::binary);
    out << "P5\n# CONCERT occupancy grid\n" << grid.width << " " << grid.height << "\n255\n";
    std::string row(static_cast<std::size_t>(grid.width), '\0');
    for (int r = grid.height - 1; r >= 0; --r) {  // the image's first row is the map's top
      for (int c = 0; c < grid.width; ++c) {
        const std::int8_t v = grid.at(c, r);
        row[static_cast<std::size_t>(c)] = static_cast<char>(v == OccupancyGrid::kOccupied ? 0
                                                             : v == OccupancyGrid::kFree   ? 254
                                                                                           : 205);
      }
      out.write(row.data(), static_cast<std::streamsize>(row.size()));
    }
    if (!out) throw MapError("save_map: cannot write '" + pgm.string() + "'");
  }
  const fs::path yaml = fs::path(dir) / (stem + ".yaml");
  std::ofstream out(yaml);
  out.precision(10);
  out << "image: " << stem << ".pgm\n"
      << "mode: trinary\n"
      << "resolution: " << grid.resolution << "\n"
      << "origin: [" << grid.origin.x() << ", " << grid.origin.y() << ", 0.0]\n"
      << "negate: 0\n"
      << "occupied_thresh: 0.65\n"
      << "free_thresh: 0.196\n";
  if (!out) throw MapError("save_map: cannot write '" + yaml.string() + "'");
}

namespace {

// Next token of a PGM header, skipping whitespace and '#' comments.
std::string pgm_token(std::istream& in, const std::string& file) {
  std::string tok;
  while (true) {
    const int ch = in.get();
    if (ch == EOF) break;
    if (ch == '#') {
      std::string skip;
      std::getline(in, skip);
      if (!tok.empty()) break;
      continue;
    }
    if (std::isspace(ch)) {
      if (!tok.empty()) break;
      continue;
    }
    tok.push_back(static_cast<char>(ch));
  }
  if (tok.empty()) throw MapError("map image '" + file + "': truncated header");
  return tok;
}

int pgm_int(std::istream& in, const std::string& file, const char* field) {
  const std::string tok = pgm_token(in, file);
  try {
    std::size_t used = 0;
    const int v = std::stoi(tok, &used);
    if (used == tok.size() && v > 0) return v;
  } catch (const std::exception&) {
  }
  throw MapError("map image '" + file + "': " + field + " '" + tok + "' is not a positive integer");
}

}  // namespace

OccupancyGrid load_map(const std::string& yaml_path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const std::exception& e) {
    throw MapError("map file '" + yaml_path + "': " + e.what());
  }
  auto field = [&](const char* name) {
    if (!root.IsMap() || !root[name])
      throw MapError("map file '" + yaml_path + "': missing field '" + name + "'");
    return root[name];
  };
  MapMetadata meta;
  try {
    meta.image = field("image").as<std::string>();
    meta.resolution = field("resolution").as<double>();
    const auto o = field("origin");
    if (!o.IsSequence() || o.size() != 3)
      throw MapError("map file '" + yaml_path + "': origin: expected [x, y, yaw]");
    meta.origin = {o[0].as<double>(), o[1].as<double>(), o[2].as<double>()};
    if (root["negate"]) meta.negate = root["negate"].as<int>() != 0;
    if (root["occupied_thresh"]) meta.occupied_thresh = root["occupied_thresh"].as<double>();
    if (root["free_thresh"]) meta.free_thresh = root["free_thresh"].as<double>();
    if (root["mode"]) meta.mode = root["mode"].as<std::string>();
  } catch (const MapError&) {
    throw;
  } catch (const std::exception& e) {
    throw MapError("map file '" + yaml_path + "': " + e.what());
  }
  if (!(meta.resolution > 0.0))
    throw MapError("map file '" + yaml_path + "': resolution: must be > 0");
  if (meta.mode != "trinary") {
    throw MapError("map file '" + yaml_path + "': mode '" + meta.mode +
                   "': only trinary maps are read");
  }
  if (std::abs(meta.origin.z()) > 1e-9) {
    throw MapError("map file '" + yaml_path +
                   "': origin: a rotated map (yaw != 0) is not supported");
  }
  fs::path image = meta.image;
  if (image.is_relative()) image = fs::path(yaml_path).parent_path() / image;
  std::ifstream in(image, std::ios::binary);
  if (!in)
    throw MapError("map file '" + yaml_path + "': image '" + image.string() + "' cannot be opened");
  const std::string file = image.string();
  const std::string magic = pgm_token(in, file);
  if (magic != "P5" && magic != "P2") {
    throw MapError("map image '" + file + "': '" + magic + "' is not a PGM (P5 or P2) image");
  }
  const int w = pgm_int(in, file, "width");
  const int h = pgm_int(in, file, "height");
  const int maxval = pgm_int(in, file, "maxval");
  if (maxval > 255) throw MapError("map image '" + file + "': 16-bit PGM images are not supported");
  OccupancyGrid grid =
      OccupancyGrid::filled(w, h, meta.resolution, meta.origin.head<2>(), OccupancyGrid::kUnknown);
  for (int r = h - 1; r >= 0; --r) {
    for (int c = 0; c < w; ++c) {
      int v = 0;
      if (magic == "P5") {
        const int ch = in.get();
        if (ch == EOF) {
          throw MapError("map image '" + file + "': truncated: " + std::to_string(w * h) +
                         " pixels expected");
        }
        v = ch;
      } else {
        if (!(in >> v)) {
          throw MapError("map image '" + file + "': truncated: " + std::to_string(w * h) +
                         " pixels expected");
        }
      }
      // map_server: occupancy = (255 - v) / 255 unless negated.
      const double occ = meta.negate ? v / static_cast<double>(maxval)
                                     : (maxval - v) / static_cast<double>(maxval);
      grid.at(c, r) = occ > meta.occupied_thresh ? OccupancyGrid::kOccupied
                      : occ < meta.free_thresh   ? OccupancyGrid::kFree
                                                 : OccupancyGrid::kUnknown;
    }
  }
  return grid;
}

}  // namespace concert::bim
