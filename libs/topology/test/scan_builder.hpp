#pragma once
// Helpers of the reconstruction tests (hand-written scans: concert/simbus/testing.hpp).

#include <string>
#include <utility>

#include "concert/common/error_text.hpp"

#include "concert/simbus/testing.hpp"
#include "concert/topology/reconstruction.hpp"

namespace concert::topology::test {

using namespace concert::simbus::testing;

/// Message of the DiscoveryError `f` throws, or "" if it does not throw one.
template <class F>
std::string discovery_error(F&& f) {
  return error_text<DiscoveryError>(std::forward<F>(f), "");
}

/// Message of the DiscoveryError that discover(scan, catalog, params) throws, or "".
inline std::string discover_error(const EscScan& scan, const EscCatalog& catalog,
                                  const DiscoveryParams& params = {}) {
  return discovery_error([&] { (void)discover(scan, catalog, params); });
}

}  // namespace concert::topology::test
