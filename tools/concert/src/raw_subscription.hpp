#pragma once
// The tool's name for libs/dds's reader of any topic (concert/dds/raw_subscription.hpp).
#include "concert/dds/raw_subscription.hpp"

namespace concert::tool {
using dds::from_catalogue;
using dds::RawSubscription;
using dds::Resolved;
}  // namespace concert::tool
