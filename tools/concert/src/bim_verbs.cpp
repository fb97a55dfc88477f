#include "bim_verbs.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <algorithm>
#include <map>
#include <optional>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "concert/bim/geometry.hpp"
#include "concert/bim/model.hpp"
#include "concert/bim/storey_map.hpp"
#include "concert/bim/wall_goal.hpp"
#include "concert/dds/endpoint.hpp"
#include "concert/dds/participant.hpp"

namespace concert::tool {
namespace {

namespace fs = std::filesystem;
using cli::Failure;
using cli::UsageError;
using Json = nlohmann::ordered_json;

/// The index of an import folder: which sub-folder holds which storey's map.
constexpr const char* kIndex = "bim.json";

struct ImportOptions {
  std::string file;
  std::string out;
  std::string storey;
  double resolution{0.05};
  std::vector<double> band{0.10, 1.90};
  bool json{false};
};

struct GoalOptions {
  std::string wall;
  std::vector<double> at;
  std::string bim_dir;
  std::string storey;
  double standoff{0.0};      ///< 0: from the running nav service's vehicle, else kDefaultStandoff
  double robot_radius{0.0};  ///< 0: likewise, else kDefaultRobotRadius
  std::string face{"auto"};
  cli::DdsOptions dds;  ///< --domain/--timeout: where to ask nav for the vehicle; --json
};

// Without a running nav service (and without --standoff / --robot-radius): a base of about the
// CONCERT platform's size.
constexpr double kDefaultStandoff = 0.8;
constexpr double kDefaultRobotRadius = 0.4;
// Footprint front edge to the wall face: nav's default wall_clearance (services/nav/config/nav.yaml).
constexpr double kWallClearance = 0.25;

// The standoff and robot radius of the mounted model, as the nav service recognised it
// (concert/nav/vehicle, latched): the footprint's front edge + kWallClearance, and its
// inscribed radius. Empty when no nav service answers or the model cannot navigate.
std::optional<std::pair<double, double>> live_vehicle(const cli::DdsOptions& dds, std::string& source) {
  dds::Participant participant({.name = "concert_bim", .domain_id = dds.domain_id()});
  dds::Reader<msg::NavVehicle> vehicles(participant, dds::topics::nav_vehicle);
  const auto v = vehicles.wait(dds.timeout());
  if (!v || v->drive().empty() || v->footprint().empty()) return std::nullopt;
  double front = 0.0;
  std::vector<Eigen::Vector2d> polygon;
  for (const auto& p : v->footprint()) {
    front = std::max(front, p.x());
    polygon.emplace_back(p.x(), p.y());
  }
  // Inscribed radius about the base origin: the nearest polygon edge.
  double inscribed = 1e9;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d a = polygon[i], b = polygon[(i + 1) % polygon.size()];
    const Eigen::Vector2d e = b - a;
    const double t = std::clamp(-a.dot(e) / std::max(1e-12, e.squaredNorm()), 0.0, 1.0);
    inscribed = std::min(inscribed, (a + t * e).norm());
  }
  source = "model version " + std::to_string(v->model_version()) + " (" + v->drive() + ")";
  return std::make_pair(front + kWallClearance, inscribed);
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void write_text(const fs::path& file, const std::string& text) {
  std::ofstream out(file);
  out << text;
  if (!out) throw Failure("cannot write '" + file.string() + "'");
}

int run_import(const ImportOptions& o, std::ostream& out) {
  if (o.band.size() != 2 || !(o.band[1] > o.band[0])) {
    throw UsageError("--band MIN MAX: two heights above the storey elevation with MIN < MAX [m]");
  }
  const auto t0 = std::chrono::steady_clock::now();
  bim::BimModel model;
  try {
    model = bim::load_ifc(o.file, {.keep_dir = o.out});
  } catch (const bim::BimError& e) {
    throw Failure(e.what());
  }
  const double import_s = seconds_since(t0);
  std::vector<const bim::Storey*> storeys;
  try {
    if (o.storey.empty()) {
      for (const auto& s : model.storeys) storeys.push_back(&s);
    } else {
      storeys.push_back(&model.storey(o.storey));
    }
  } catch (const bim::BimError& e) {
    throw Failure(e.what());
  }
  const bim::SliceParams params{
      .band_min = o.band[0], .band_max = o.band[1], .resolution = o.resolution};
  Json index_storeys = Json::array();
  Json report_storeys = Json::array();
  std::set<std::string> used;
  std::ostringstream text;
  for (const bim::Storey* s : storeys) {
    std::string dir = bim::slug(s->name);
    for (int k = 2; used.count(dir) != 0; ++k) dir = bim::slug(s->name) + "-" + std::to_string(k);
    used.insert(dir);
    std::map<std::string, int> counts;
    for (const bim::Element* e : model.elements_of(*s)) ++counts[e->ifc_type];
    Json entry{
        {"name", s->name}, {"global_id", s->global_id}, {"elevation", s->elevation}, {"dir", dir}};
    Json report = entry;
    report["elements"] = counts;
    text << "storey '" << s->name << "' (elevation " << std::fixed << std::setprecision(3)
         << s->elevation << " m) -> " << (fs::path(o.out) / dir).string() << "\n  elements:";
    for (const auto& [type, n] : counts) text << " " << type << " " << n;
    if (counts.empty()) text << " none";
    text << "\n";
    bim::OccupancyGrid grid;
    try {
      const auto t1 = std::chrono::steady_clock::now();
      grid = bim::storey_map(model, *s, params);
      const double map_s = seconds_since(t1);
      bim::save_map(grid, (fs::path(o.out) / dir).string(), "map");
      write_text(fs::path(o.out) / dir / "geometry.json", bim::geometry_json(model, *s) + "\n");
      std::size_t occupied = 0;
      for (const auto c : grid.cells) occupied += c == bim::OccupancyGrid::kOccupied ? 1 : 0;
      report["map"] =
          Json{{"width", grid.width},
               {"height", grid.height},
               {"resolution", grid.resolution},
               {"size_m", {grid.width * grid.resolution, grid.height * grid.resolution}},
               {"origin", {grid.origin.x(), grid.origin.y()}},
               {"occupied_cells", occupied},
               {"time_s", map_s}};
      text << "  map: " << grid.width << " x " << grid.height << " cells, " << std::setprecision(2)
           << grid.width * grid.resolution << " x " << grid.height * grid.resolution << " m at "
           << grid.resolution << " m, origin (" << grid.origin.x() << ", " << grid.origin.y()
           << "), " << occupied << " occupied cells, " << std::setprecision(3) << map_s << " s\n";
    } catch (const bim::BimError& e) {
      // A storey without geometry (e.g. a roof level holding nothing) gets no map; others do.
      report["map"] = nullptr;
      report["error"] = e.what();
      text << "  no map: " << e.what() << "\n";
      entry["dir"] = nullptr;
    }
    index_storeys.push_back(entry);
    report_storeys.push_back(report);
  }
  const Json index{{"format", "concert-bim-import"}, {"version", 1},   {"source", model.source},
                   {"model", "model.json"},          {"band", o.band}, {"resolution", o.resolution},
                   {"storeys", index_storeys}};
  write_text(fs::path(o.out) / kIndex, index.dump(1) + "\n");
  const double total_s = seconds_since(t0);
  if (o.json) {
    out << Json{{"source", model.source}, {"schema", model.schema}, {"out", o.out},
                {"import_s", import_s},   {"total_s", total_s},     {"storeys", report_storeys}}
               .dump()
        << "\n";
  } else {
    out << "concert bim import: " << model.source << " (" << model.schema << ", "
        << model.storeys.size() << " storeys, " << model.elements.size()
        << " elements), IFC import " << std::fixed << std::setprecision(2) << import_s << " s\n"
        << text.str() << "total " << std::setprecision(2) << total_s << " s\n";
  }
  return 0;
}

int run_goal(const GoalOptions& o, std::ostream& out) {
  if (o.at.size() != 2)
    throw UsageError("--at S H: axis distance from the wall's start and height [m]");
  const fs::path dir(o.bim_dir);
  const fs::path index_file = dir / kIndex;
  std::ifstream in(index_file);
  if (!in)
    throw Failure("--bim " + o.bim_dir + ": no " + kIndex + " (make it with `concert bim import`)");
  Json index;
  try {
    index = Json::parse(in);
  } catch (const Json::exception& e) {
    throw Failure(index_file.string() + ": not JSON: " + e.what());
  }
  try {
    const bim::BimModel model =
        bim::read_import((dir / index.at("model").get<std::string>()).string());
    const bim::Element& wall = model.element(o.wall);
    const bim::Storey& storey = model.storey(o.storey.empty() ? wall.storey : o.storey);
    std::string map_dir;
    for (const auto& s : index.at("storeys")) {
      if (s.at("global_id") == storey.global_id && s.at("dir").is_string()) map_dir = s.at("dir");
    }
    if (map_dir.empty()) {
      throw Failure("--bim " + o.bim_dir + ": no map of storey '" + storey.name +
                    "' (import it with `concert bim import --storey`)");
    }
    const bim::OccupancyGrid grid = bim::load_map((dir / map_dir / "map.yaml").string());
    bim::GoalOptions options;
    options.face = bim::face_choice(o.face);
    double standoff = o.standoff, robot_radius = o.robot_radius;
    std::string sizes = "given";
    if (standoff <= 0.0 || robot_radius <= 0.0) {
      std::string source;
      const auto live = live_vehicle(o.dds, source);
      sizes = live ? "from the running " + source : "defaults (no nav service running)";
      if (standoff <= 0.0) standoff = live ? live->first : kDefaultStandoff;
      if (robot_radius <= 0.0) robot_radius = live ? live->second : kDefaultRobotRadius;
    }
    const bim::WallGoal g =
        bim::wall_goal(model, grid, o.wall, o.at[0], o.at[1], standoff, robot_radius, options);
    const Eigen::Vector3d p = g.area_frame.translation();
    const Eigen::Matrix3d r = g.area_frame.linear();
    const Eigen::Quaterniond q(r);
    if (o.dds.json) {
      auto v3 = [](const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); };
      out << Json{{"wall", o.wall},
                  {"storey", g.storey},
                  {"face", g.face == 0 ? "left" : "right"},
                  {"area_frame",
                   {{"position", v3(p)},
                    {"x", v3(r.col(0))},
                    {"y", v3(r.col(1))},
                    {"z", v3(r.col(2))},
                    {"quaternion_xyzw", {q.x(), q.y(), q.z(), q.w()}}}},
                  {"base_pose",
                   {{"x", g.base_pose.x()}, {"y", g.base_pose.y()}, {"theta", g.base_pose.z()}}},
                  {"free_area_m2", g.free_area},
                  {"standoff", standoff},
                  {"robot_radius", robot_radius},
                  {"sizes", sizes}}
                 .dump()
          << "\n";
    } else {
      out << std::fixed << std::setprecision(3) << "wall " << o.wall << " (" << wall.ifc_type
          << " \"" << wall.name << "\"), storey '" << g.storey << "', "
          << (g.face == 0 ? "left" : "right") << " face\n"
          << "area frame: origin (" << p.x() << ", " << p.y() << ", " << p.z() << ") m, x ("
          << r(0, 0) << ", " << r(1, 0) << ", " << r(2, 0) << "), z = face normal (" << r(0, 2)
          << ", " << r(1, 2) << ", " << r(2, 2) << "), quaternion xyzw (" << q.x() << ", " << q.y()
          << ", " << q.z() << ", " << q.w() << ")\n"
          << "base pose: x " << g.base_pose.x() << " m, y " << g.base_pose.y() << " m, theta "
          << g.base_pose.z() << " rad (" << std::setprecision(1) << g.base_pose.z() * 180 / M_PI
          << " deg)\n";
    }
  } catch (const bim::BimError& e) {
    throw Failure(e.what());
  } catch (const bim::MapError& e) {
    throw Failure(e.what());
  } catch (const Json::exception& e) {
    throw Failure(index_file.string() + ": " + e.what());
  }
  return 0;
}

}  // namespace

void register_bim_verbs(cli::Cli& concert) {
  CLI::App& bim =
      concert.group(concert.app(), "bim", "the building's IFC model: maps, geometry, wall goals");

  auto im = std::make_shared<ImportOptions>();
  CLI::App& import = concert.verb(
      bim, "import",
      "IFC file -> per storey an occupancy map (nav2 map.yaml + map.pgm) and geometry.json",
      [&concert, im] { return run_import(*im, concert.out()); });
  import.add_option("FILE", im->file, "an IFC2x3 or IFC4 file")->required();
  import.add_option("--out", im->out, "output folder (one sub-folder per storey)")
      ->required()
      ->type_name("DIR");
  import
      .add_option("--storey", im->storey,
                  "only this storey (name or GlobalId; default: every storey)")
      ->type_name("NAME");
  import.add_option("--resolution", im->resolution, "map cell side [m]")
      ->check(cli::number(0.001, 10))
      ->default_str("0.05");
  import.add_option("--band", im->band, "slice band above the storey elevation [m]")
      ->expected(2)
      ->type_name("MIN MAX")
      ->check(cli::real())
      ->default_str("0.10 1.90");
  import.add_flag("--json", im->json, "machine-readable summary");

  auto go = std::make_shared<GoalOptions>();
  CLI::App& goal = concert.verb(
      bim, "goal", "area frame on a wall face at (S, H) and the base pose in front of it",
      [&concert, go] { return run_goal(*go, concert.out()); });
  goal.add_option("--wall", go->wall, "the wall's IFC GlobalId")->required()->type_name("GLOBALID");
  goal.add_option("--at", go->at,
                  "axis distance from the wall's start, height above its storey [m]")
      ->required()
      ->expected(2)
      ->type_name("S H")
      ->check(cli::real());
  goal.add_option("--bim", go->bim_dir, "a folder written by `concert bim import`")
      ->required()
      ->type_name("DIR");
  goal.add_option("--storey", go->storey, "the storey whose map to use (default: the wall's)")
      ->type_name("NAME");
  goal.add_option("--standoff", go->standoff,
                  "distance from the face to the base's centre [m] (default: the running robot's "
                  "footprint front + 0.25 m, as nav computes it; 0.8 without a nav service)")
      ->check(cli::number(0, 1e3, false, true));
  goal.add_option("--robot-radius", go->robot_radius,
                  "radius of the base's footprint disc [m] (default: the running robot's inscribed "
                  "radius; 0.4 without a nav service)")
      ->check(cli::number(0, 1e3, false, true));
  cli::Cli::add_choice(goal, "--face", go->face, {"auto", "left", "right"},
                       "which face (left/right of the wall's axis; auto: the reachable one)");
  concert.add_dds_options(goal, go->dds, 1.5,
                          "how long to wait for the nav service's vehicle (sizes not given)");
}

}  // namespace concert::tool
