#include "conversions.hpp"

#include <stdexcept>

namespace concert::modelgen::dds {

CustomisationRequest to_core(const msg::ModelCustomisation& request) {
  CustomisationRequest out;
  out.request_id = request.request_id();
  out.base_version = request.base_version();
  if (request.homing_joints().size() != request.homing_positions().size()) {
    throw std::invalid_argument("customisation request " + std::to_string(request.request_id()) + ": " +
                                std::to_string(request.homing_joints().size()) + " homing joints but " +
                                std::to_string(request.homing_positions().size()) + " positions");
  }
  for (size_t i = 0; i < request.homing_joints().size(); ++i) {
    if (!out.customisation.home.emplace(request.homing_joints()[i], request.homing_positions()[i]).second) {
      throw std::invalid_argument("customisation request " + std::to_string(request.request_id()) + ": joint '" +
                                  request.homing_joints()[i] + "' listed twice");
    }
  }
  for (const msg::AddonChoice& a : request.addons()) out.customisation.addons.push_back({a.module_name(), a.addon()});
  return out;
}

}  // namespace concert::modelgen::dds
