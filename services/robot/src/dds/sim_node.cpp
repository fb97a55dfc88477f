#include "sim_node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "concert/common/clock.hpp"
#include "concert/model/dds/pose.hpp"
#include "concert/world/world_dds.hpp"
#include "robot_conversions.hpp"

namespace concert::robot::dds {

namespace cdds = concert::dds;

namespace {

/// Writes `text` over `path` through a temporary file and a rename, so a simulator started
/// meanwhile reads the old content or the new, never half of it. "" when written, else why not.
std::string write_over(const std::string& path, const std::string& text) {
  if (path.empty()) return "";
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << text;
    if (!out.flush()) return "cannot write " + tmp;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  return ec ? "cannot rename " + tmp + " to " + path + ": " + ec.message() : "";
}

/// "; not kept in FILE: why" when writing back failed (the change itself stands).
std::string kept(const std::string& path, const std::string& text) {
  const std::string error = write_over(path, text);
  if (error.empty()) return "";
  std::cerr << "concert_robot: " << error << "\n";
  return "; not kept for a restart: " + error;
}

}  // namespace

SimNode::SimNode(cdds::Participant& participant, sim::SimHardware& sim,
                 const sim::AssemblyBuilder* builder, RobotNode& robot,
                 const world::World& initial_world, const std::string& world_source,
                 std::function<void(const sim::SimulatedRobot&)> on_swap, Keep keep)
    : sim_(sim),
      builder_(builder),
      robot_(robot),
      on_swap_(std::move(on_swap)),
      keep_(std::move(keep)),
      world_(participant, cdds::topics::world),
      reply_(participant, cdds::topics::sim_reply),
      truth_(participant, cdds::topics::sim_truth),
      holes_(participant, cdds::topics::sim_holes) {
  world_.write(world::to_msg(initial_world, world_version_, world_source));
  worker_ = std::thread([this] { work(); });
  truth_thread_ = std::thread([this] { publish_truth(); });
  commands_ = std::make_unique<cdds::Reader<msg::SimCommand>>(
      participant, cdds::topics::sim_command, [this](const msg::SimCommand& c, const auto&) {
        {
          std::lock_guard lock(mutex_);
          queue_.push_back(c);
        }
        wake_.notify_all();
      });
}

SimNode::~SimNode() {
  commands_.reset();
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  worker_.join();
  truth_thread_.join();
}

void SimNode::publish_truth() {
  constexpr auto kPeriod = std::chrono::milliseconds(20);
  std::unique_lock lock(mutex_);
  double last_time = -1.0;
  while (!wake_.wait_for(lock, kPeriod, [&] { return stopping_; })) {
    lock.unlock();
    const auto truth = sim_.base_truth();
    if (truth.time != last_time) {  // nothing new while the loop is paused
      last_time = truth.time;
      const Eigen::Matrix3d& r = truth.pose.linear();
      msg::SimTruth t;
      t.stamp_ns(static_cast<long long>(std::llround(truth.time * 1e9)));
      t.x(truth.pose.translation().x());
      t.y(truth.pose.translation().y());
      t.z(truth.pose.translation().z());
      t.yaw(std::atan2(r(1, 0), r(0, 0)));
      t.pitch(std::asin(std::clamp(-r(2, 0), -1.0, 1.0)));
      t.roll(std::atan2(r(2, 1), r(2, 2)));
      truth_.write(t);
      publish_holes(truth.time);
    }
    lock.lock();
  }
}

// The drilled holes, rewritten whenever one opens or deepens (latched: a late reader gets them).
void SimNode::publish_holes(double time) {
  std::vector<sim::SimHole> holes = sim_.holes();
  double depth_sum = 0.0;
  for (const auto& h : holes) depth_sum += h.depth;
  if (holes.size() == holes_count_ && depth_sum == holes_depth_sum_) return;
  holes_count_ = holes.size();
  holes_depth_sum_ = depth_sum;
  msg::SimHoles m;
  m.stamp_ns(static_cast<long long>(std::llround(time * 1e9)));
  for (const auto& h : holes) {
    msg::SimHole out;
    out.wall(h.wall);
    out.bit(h.bit);
    out.entry(model::dds::to_vector_msg(h.entry));
    out.axis(model::dds::to_vector_msg(h.axis));
    out.face_normal(model::dds::to_vector_msg(h.face_normal));
    out.depth(h.depth);
    out.diameter(h.diameter);
    out.started(h.time);
    m.holes().push_back(out);
  }
  holes_.write(m);
}

void SimNode::work() {
  std::unique_lock lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (stopping_) {
      return;
    }
    const msg::SimCommand c = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    handle(c);
    lock.lock();
  }
}

void SimNode::handle(const msg::SimCommand& c) {
  const std::pair<std::uint32_t, std::int64_t> key{c.request_id(), c.stamp_ns()};
  for (const auto& [k, r] : answered_) {
    if (k == key) {
      reply_.write(r);  // a resent command: its answer again, nothing applied twice
      return;
    }
  }
  msg::SimCommandReply reply;
  reply.request_id(c.request_id());
  const bool person_order = c.kind() == msg::SIM_PERSON;
  const std::string what = c.kind() == msg::SIM_SWAP_ASSEMBLY ? "assembly" : person_order ? "person" : "world";
  const std::string kept = c.kind() == msg::SIM_SWAP_ASSEMBLY ? "modules" : person_order ? "person as it is" : "world";
  bool quiet = false;  // a status query is not news in the log
  try {
    if (person_order) {
      reply.message(person(c.content(), c.name(), quiet));
    } else {
      reply.message(c.kind() == msg::SIM_SWAP_ASSEMBLY ? swap_assembly(c.content(), c.name())
                                                       : set_world(c.content(), c.name()));
    }
    reply.accepted(true);
    if (!quiet)
      std::cerr << "concert_robot: " << what << " from '" << c.name() << "' (" << c.source()
                << "): " << reply.message() << "\n";
  } catch (const std::exception& e) {
    reply.accepted(false);
    reply.message(what + " '" + c.name() + "' refused, the simulator keeps its " + kept + ": " + e.what());
    std::cerr << "concert_robot: " << reply.message() << "\n";
  }
  reply.stamp_ns(now_ns());
  reply_.write(reply);
  answered_.emplace_back(key, reply);
  constexpr std::size_t kAnswersKept = 64;
  if (answered_.size() > kAnswersKept) answered_.pop_front();
}

std::string SimNode::person(const std::string& yaml, const std::string& name, bool& status) {
  const std::optional<world::PersonOrder> order = world::parse_person_order(yaml, name);
  status = !order;
  if (!order) return world::person_report_yaml(sim_.person_report());
  return sim_.person(*order);
}

std::string SimNode::swap_assembly(const std::string& yaml, const std::string& name) {
  if (builder_ == nullptr) {
    throw std::runtime_error(
        "the simulated robot is a fixed URDF (--urdf): there is no assembly to swap");
  }
  const sim::SimulatedRobot robot = builder_->build_from_text(yaml, name);
  if (!sim_.swap_model(robot)) {
    return "the same robot is mounted again: nothing changed";
  }
  // The loop switches at its next cycle boundary; mounted() already names the new joints, so
  // a model made from this scan is checked against them.
  robot_.publish_scan(robot.scan, "sim");
  if (on_swap_) {
    on_swap_(robot);
  }
  return "mounted: " + std::to_string(robot.scan.slaves.size()) + " EtherCAT slaves, " +
         std::to_string(robot.tree.modules.size()) + " modules" + kept(keep_.assembly_file, yaml);
}

std::string SimNode::set_world(const std::string& yaml, const std::string& name) {
  const world::World w = world::parse_world_yaml(yaml, name);
  sim_.set_world(w);
  std::uint32_t version = 0;
  {
    std::lock_guard lock(mutex_);
    version = ++world_version_;
  }
  world_.write(world::to_msg(w, version, name));
  return "world version " + std::to_string(version) + ": " + std::to_string(w.walls.size()) +
         " walls, " + std::to_string(w.obstacles.size()) + " obstacles, " +
         std::to_string(w.marks.size()) + " marks, " + std::to_string(w.surfaces.size()) +
         " surfaces" + kept(keep_.world_file, yaml);
}

}  // namespace concert::robot::dds
