// Contract peer on Cyclone DDS, using idlc's generated C types (through cyclone_ops.c).
#include <cstdlib>
#include <thread>

#include "concert/security/dds_config.hpp"
#include "cyclone_ops.h"
#include "peer_common.hpp"

using namespace concert;
using namespace std::chrono_literals;

int main(int argc, char** argv) try {
  const auto args = contract::parse_peer_args(argc, argv);
  const auto& schema = idl::Schema::builtin();
  // CONCERT_SECURITY: secured with Cyclone's plugins, as the identity the Fast DDS peers would
  // take (CONCERT_SECURITY_IDENTITY, else operator).
  std::string security;
  if (const auto pki = security::pki_from_environment()) {
    const auto files = security::identity_files(*pki, security::resolve_identity("", "contract_cyclone"));
    security::check_identity(files);
    security = security::cyclone_security_config(files, CONCERT_CYCLONE_SECURITY_PLUGINS);
  }
  if (cy_open(dds::domain_id_from_env(), security.empty() ? nullptr : security.c_str()) != 0) return 2;
  // Cyclone's threads stopped on every way out, before exit() runs OpenSSL's cleanup under them.
  struct CloseAtExit {
    ~CloseAtExit() { cy_close(); }
  } close_at_exit;

  struct Endpoint {
    dds::TopicInfo info;
    int handle;
    bool done = false;
  };
  std::vector<Endpoint> endpoints;
  for (const auto& info : args.topics) {
    const auto spec = dds::qos_spec(info.qos);
    const cy_qos q{spec.reliable, spec.transient_local, spec.history_depth};
    const std::string name(info.name), type(info.type_name);
    const int h = args.write ? cy_create_writer(name.c_str(), type.c_str(), q)
                             : cy_create_reader(name.c_str(), type.c_str(), q);
    if (h < 0) return 2;
    endpoints.push_back({info, h});
  }

  const auto start = std::chrono::steady_clock::now();
  if (args.write) {
    for (auto& ep : endpoints) {
      cy_qos remote{};
      if (args.wait_readers) {
        while (cy_matched(ep.handle, &remote) < 1) {
          if (contract::past(start, args.timeout_ms)) {
            std::cerr << "contract_peer_cyclone: no reader matched on " << ep.info.name << std::endl;
            return 1;
          }
          std::this_thread::sleep_for(10ms);
        }
      }
      if (args.stale_first) {
        const auto stale = idl::encode(schema, ep.info.type_name, contract::stale_sample(ep.info, args.seed));
        if (cy_write(ep.handle, stale.data(), stale.size()) != 0) return 2;
      }
      const auto bytes = idl::encode(schema, ep.info.type_name, contract::expected_sample(ep.info, args.seed, args.full_images));
      if (cy_write(ep.handle, bytes.data(), bytes.size()) != 0) return 2;
      cy_qos local{};
      if (cy_local(ep.handle, &local) != 0) return 2;
      idl::Json event = {{"event", "written"}, {"topic", ep.info.name},
                         {"local_qos", contract::qos_json(local.reliable, local.transient_local, local.depth)}};
      if (args.wait_readers) event["remote_qos"] = contract::qos_json(remote.reliable, remote.transient_local, -1);
      contract::emit(event);
    }
    auto last = std::chrono::steady_clock::now();
    while (!contract::past(start, args.linger_ms)) {
      if (args.repeat_ms > 0 && contract::past(last, args.repeat_ms)) {
        for (auto& ep : endpoints) {
          const auto bytes = idl::encode(schema, ep.info.type_name, contract::expected_sample(ep.info, args.seed, args.full_images));
          cy_write(ep.handle, bytes.data(), bytes.size());
        }
        last = std::chrono::steady_clock::now();
      }
      std::this_thread::sleep_for(10ms);
    }
    return 0;
  }

  size_t remaining = endpoints.size();
  while (remaining > 0 && !contract::past(start, args.timeout_ms)) {
    for (auto& ep : endpoints) {
      if (ep.done) continue;
      uint8_t *wire = nullptr, *reser = nullptr;
      size_t wire_len = 0, reser_len = 0;
      const int got = cy_take(ep.handle, &wire, &wire_len, &reser, &reser_len);
      if (got < 0) return 2;
      if (got == 0) continue;
      cy_qos remote{};
      cy_matched(ep.handle, &remote);
      cy_qos local{};
      if (cy_local(ep.handle, &local) != 0) return 2;
      contract::emit({{"event", "received"}, {"topic", ep.info.name},
                      {"sample", idl::decode(schema, ep.info.type_name, {reser, reser_len})},
                      {"wire", idl::representation({wire, wire_len})},
                      {"local_qos", contract::qos_json(local.reliable, local.transient_local, local.depth)},
                      {"remote_qos", contract::qos_json(remote.reliable, remote.transient_local, -1)}});
      std::free(wire);
      std::free(reser);
      ep.done = true;
      --remaining;
    }
    std::this_thread::sleep_for(5ms);
  }
  return contract::report_missing(endpoints);
} catch (const std::exception& e) {
  std::cerr << "contract_peer_cyclone: " << e.what() << std::endl;
  return 2;
}
