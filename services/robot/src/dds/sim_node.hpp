#pragma once
// DDS face of the simulator (the robot service's sim backend): SimCommand in (mount another
// assembly, change the world, tell the simulated person what to do: the content travels, so it
// works from any host), SimCommandReply
// out (accepted, or refused with the reason: the robot keeps its modules and world), and the
// world it simulates on the latched World topic that every service reads; and the base's true
// pose (SimTruth, 50 Hz) for tests and benchmarks.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "concert/dds/endpoint.hpp"
#include "concert/sim/sim_assembly.hpp"
#include "concert/sim/sim_hardware.hpp"
#include "robot_node.hpp"

namespace concert::robot::dds {

class SimNode {
 public:
  /// Where accepted swaps and worlds are written back (`concert_robot --keep-swaps`), so that
  /// a restarted simulator mounts what was mounted and simulates the world it simulated: the
  /// modules of a real robot stay bolted on when its software dies. Empty: not kept.
  struct Keep {
    std::string assembly_file;
    std::string world_file;
  };

  /// `builder` is null when the simulated robot is a fixed URDF (no assembly to swap).
  /// `on_swap` runs after each accepted swap (e.g. standalone mode applies the new model).
  /// Publishes `initial_world` (from `world_source`) as world version 1.
  SimNode(concert::dds::Participant& participant, sim::SimHardware& sim, const sim::AssemblyBuilder* builder,
          RobotNode& robot, const world::World& initial_world, const std::string& world_source,
          std::function<void(const sim::SimulatedRobot&)> on_swap = {}, Keep keep = {});
  ~SimNode();
  SimNode(const SimNode&) = delete;
  SimNode& operator=(const SimNode&) = delete;

  /// Mounts the assembly in `yaml` (named `name` in messages): checks it, prepares the new
  /// MuJoCo robot off the loop, publishes the new scan. Returns what happened; throws
  /// std::runtime_error with the reason when refused (nothing changes).
  std::string swap_assembly(const std::string& yaml, const std::string& name);
  /// Replaces the world the same way, and publishes it.
  std::string set_world(const std::string& yaml, const std::string& name);
  /// An order to the simulated person (sim/person_order.hpp): what will happen, or for a
  /// status query (`status` set) the person's state as one line of YAML. Throws with the reason.
  std::string person(const std::string& yaml, const std::string& name, bool& status);

 private:
  void work();
  void publish_truth();
  void publish_holes(double time);
  void handle(const msg::SimCommand& command);

  sim::SimHardware& sim_;
  const sim::AssemblyBuilder* builder_;
  RobotNode& robot_;
  std::function<void(const sim::SimulatedRobot&)> on_swap_;
  Keep keep_;
  concert::dds::Writer<msg::World> world_;
  concert::dds::Writer<msg::SimCommandReply> reply_;
  concert::dds::Writer<msg::SimTruth> truth_;
  concert::dds::Writer<msg::SimHoles> holes_;
  std::size_t holes_count_{0};     // what was published last (truth thread only)
  double holes_depth_sum_{0.0};
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<msg::SimCommand> queue_;
  // The latest commands answered (worker thread only): a client resends a command until it
  // hears the reply (the command topic is volatile, and the reader it waited for may have been
  // another tool's), so a command seen again (same request id and stamp) is answered again,
  // not applied twice.
  std::deque<std::pair<std::pair<std::uint32_t, std::int64_t>, msg::SimCommandReply>> answered_;
  bool stopping_{false};
  std::uint32_t world_version_{1};
  std::unique_ptr<concert::dds::Reader<msg::SimCommand>> commands_;
  std::thread worker_;  // swaps take milliseconds (model generation, MuJoCo): not on a DDS thread
  std::thread truth_thread_;
};

}  // namespace concert::robot::dds
