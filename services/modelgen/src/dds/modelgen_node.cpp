#include "modelgen_node.hpp"

#include <chrono>

#include "concert/model/dds/conversions.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "conversions.hpp"

namespace concert::modelgen::dds {

namespace {

int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

ModelgenNode::ModelgenNode(concert::dds::Participant& participant, ModelgenService& service, std::ostream& log)
    : service_(service),
      trees_(participant, concert::dds::topics::module_tree),
      requests_(participant, concert::dds::topics::customisation),
      models_(participant, concert::dds::topics::robot_model),
      status_(participant, "modelgen"),
      log_(log) {
  status_.report(msg::ServiceState::SERVICE_READY, 0, "waiting for a module tree");
}

void ModelgenNode::report(const Outcome& outcome, const std::string& what) {
  const uint32_t version = static_cast<uint32_t>(outcome.version);
  if (!outcome.error.empty()) {
    log_ << "modelgen: " << outcome.error << "\n";
    status_.report(version == 0 ? msg::ServiceState::SERVICE_ERROR : msg::ServiceState::SERVICE_READY, version, outcome.error);
    return;
  }
  if (outcome.published) {
    const GeneratedModel& m = *service_.current();
    models_.write(concert::model::dds::to_msg(m.description(), now_ns()));
    log_ << "modelgen: published model version " << m.version << " (" << m.content_hash << ", " << m.modules.size()
         << " modules, " << m.joints.size() << " joints) from " << what << "\n";
    status_.report(msg::ServiceState::SERVICE_READY, version, "model version " + std::to_string(version));
  } else {
    log_ << "modelgen: " << what << " gives the current model version " << version << " again; not republished\n";
    status_.note(what + ": unchanged model version " + std::to_string(version));
  }
}

Outcome ModelgenNode::handle(const msg::ModuleTree& tree) {
  const Outcome o = service_.on_tree(topology::dds::to_core(tree), tree.version());
  report(o, "tree " + std::to_string(tree.version()));
  return o;
}

Outcome ModelgenNode::handle(const msg::ModelCustomisation& request) {
  Outcome o;
  try {
    o = service_.on_customisation(to_core(request));
  } catch (const std::invalid_argument& e) {
    o = {false, service_.current() ? service_.current()->version : 0, e.what()};
  }
  report(o, "customisation request " + std::to_string(request.request_id()));
  return o;
}

int ModelgenNode::spin_once(std::chrono::milliseconds timeout) {
  int handled = 0;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    while (auto t = trees_.take()) {
      handle(*t);
      ++handled;
    }
    while (auto r = requests_.take()) {
      handle(*r);
      ++handled;
    }
    if (handled > 0 || std::chrono::steady_clock::now() >= deadline) return handled;
    if (auto t = trees_.wait(std::chrono::milliseconds(10))) {
      handle(*t);
      ++handled;
    }
  }
}

void ModelgenNode::spin(const std::atomic<bool>& stop, std::chrono::milliseconds poll) {
  while (!stop) spin_once(poll);
}

}  // namespace concert::modelgen::dds
