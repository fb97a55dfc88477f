#include "modelgen_node.hpp"

#include <chrono>

#include "concert/common/clock.hpp"
#include "concert/model/dds/conversions.hpp"
#include "concert/topology/dds/conversions.hpp"
#include "conversions.hpp"

namespace concert::modelgen::dds {

ModelgenNode::ModelgenNode(concert::dds::Participant& participant, ModelgenService& service,
                           std::ostream& log, std::chrono::milliseconds resume_wait)
    : service_(service),
      resume_wait_(resume_wait),
      statuses_(participant, concert::dds::topics::status),
      trees_(participant, concert::dds::topics::module_tree),
      requests_(participant, concert::dds::topics::customisation),
      models_(participant, concert::dds::topics::robot_model),
      status_(participant, "modelgen"),
      log_(log) {
  status_.report(msg::ServiceState::SERVICE_STARTING, 0,
                 "learning which model the services on the wire run");
}

concert::dds::ModelId ModelgenNode::current_id() const {
  if (!service_.current()) return {};
  return {static_cast<uint32_t>(service_.current()->version), service_.current()->content_hash};
}

void ModelgenNode::resume_from_wire() {
  resumed_ = true;
  // Status samples are latched per service and heartbeat every 200 ms: whatever runs on the
  // domain is heard within the wait. Our own earlier incarnation's status is not among them
  // (its writer died with it) unless it stopped cleanly, in which case it is as good a witness.
  // On a loaded machine the other processes' writers can take longer than resume_wait to
  // match: the wait goes on (up to 3 x resume_wait) while no service that runs models (not
  // discovery, which reports none) was heard, else a restarted modelgen published the running
  // model's content again as version 1.
  uint64_t version = 0;
  std::string hash;
  std::string who;
  bool heard_others = false;
  const auto start = std::chrono::steady_clock::now();
  while (true) {
    const auto deadline = start + resume_wait_ * (heard_others ? 1 : 3);
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) break;
    const auto s =
        statuses_.wait(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now));
    if (!s) continue;
    heard_others = heard_others || (s->service() != "modelgen" && s->service() != "discovery");
    if (s->model_version() > version && !s->model_hash().empty()) {
      version = s->model_version();
      hash = s->model_hash();
      who = s->service() + "@" + s->host();
    }
  }
  const uint64_t before = service_.known_version();
  service_.learn(version, hash);
  std::string note = "waiting for a module tree";
  if (version > before) {
    note += "; the services on the wire run model version " + std::to_string(version) + " (" +
            hash + ", " + who +
            "): the same content keeps that version, other content gets a higher one";
  } else if (before > 0) {
    note += "; versions continue after " + std::to_string(before) + " (bundle)";
  }
  log_ << "modelgen: " << note << std::endl;
  status_.report(msg::ServiceState::SERVICE_READY, current_id(), note);
}

void ModelgenNode::report(const Outcome& outcome, const std::string& what) {
  const uint32_t version = static_cast<uint32_t>(outcome.version);
  if (!outcome.error.empty()) {
    log_ << "modelgen: " << outcome.error << "\n";
    status_.report(
        version == 0 ? msg::ServiceState::SERVICE_ERROR : msg::ServiceState::SERVICE_READY,
        current_id(), outcome.error);
    status_.refused(outcome.error);
    return;
  }
  if (outcome.published) {
    const GeneratedModel& m = *service_.current();
    models_.write(concert::model::dds::to_msg(m.description(), now_ns()));
    log_ << "modelgen: published model version " << m.version << " (" << m.content_hash << ", " << m.modules.size()
         << " modules, " << m.joints.size() << " joints) from " << what << "\n";
    if (const std::string rest = describe(m.resting, service_.params().generator.home_torque_fraction); !rest.empty()) {
      log_ << "modelgen: " << rest << "\n";
    }
    status_.report(msg::ServiceState::SERVICE_READY, current_id(),
                   "model version " + std::to_string(version));
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
  if (!resumed_) resume_from_wire();
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
