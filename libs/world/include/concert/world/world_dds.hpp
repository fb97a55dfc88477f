#pragma once
// The one conversion between the world and its latched topic (idl/world.idl).

#include <cstdint>
#include <string>

#include "concert/world/world.hpp"
#include "world.h"

namespace concert::world {

/// The World message of `world` at `version`; `source` names where it came from.
msg::World to_msg(const World& world, std::uint32_t version, const std::string& source);
/// The world of a World message, validated as a world file is (validate_world); throws
/// WorldError "world message '<source>': <field>: <why>".
World from_msg(const msg::World& message);

}  // namespace concert::world
