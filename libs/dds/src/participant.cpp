#include "concert/dds/participant.hpp"

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <mutex>
#include <set>
#include <stdexcept>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <fastrtps/utils/IPLocator.h>

#include "concert/security/dds_config.hpp"

namespace concert::dds {

using namespace eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

namespace {

// Participants on this machine find each other by unicast to 127.0.0.1 (the well-known RTPS
// ports of the first kMaxLocalParticipants participant ids); no multicast, no other interface.
constexpr uint32_t kMaxLocalParticipants = 48;

// Once per process: a kernel that caps socket buffers below kSocketBufferBytes loses camera
// frames; say how to fix it instead of letting frames vanish silently.
void check_socket_buffer_limit() {
  static const bool checked = [] {
    std::ifstream in("/proc/sys/net/core/rmem_max");
    uint64_t rmem_max = 0;
    if (in >> rmem_max && rmem_max < kSocketBufferBytes) {
      std::cerr << "concert dds: net.core.rmem_max is " << rmem_max << " bytes, below the "
                << kSocketBufferBytes << " the localhost transport asks for: large samples (camera images) "
                << "may be lost; raise it (deploy/install-deps.sh does: sysctl -w net.core.rmem_max="
                << kSocketBufferBytes << " net.core.wmem_max=" << kSocketBufferBytes << ")\n";
    }
    return true;
  }();
  (void)checked;
}

// Once per process and domain: a warning when the domain's ports lie in the kernel's ephemeral
// port range, where domains may leak into each other (domain_port_warning).
void check_domain_ports(int32_t domain_id) {
  static std::mutex mutex;
  static std::set<int32_t> checked;
  std::lock_guard lock(mutex);
  if (!checked.insert(domain_id).second) return;
  std::ifstream in("/proc/sys/net/ipv4/ip_local_port_range");
  long low = 0;
  long high = 0;
  if (!(in >> low >> high)) return;
  const std::string warning = domain_port_warning(domain_id, low, high);
  if (!warning.empty()) std::cerr << warning << "\n";
}

// Once per process, before its first participant: samples between endpoints of one process
// travel through the transport like any other, not handed over in the process. Fast DDS 2.9's
// intra-process path races when a participant of the process is deleted and another created
// (of the kind fixed upstream later, Fast-DDS PR 5034): in planner_dds_test the second
// `concert plan` client of the process matched the planner both ways and for 20 s received
// nothing the planner wrote (3 runs in 44 beside two busy loops; 0 in 30 without the
// intra-process path). Under load a keep-last-1 reader fed from the writer's background thread
// also trips an assertion there (ReaderProxy::from_unsent_to_status: the safety service reads
// its own heartbeat). A service runs one participant; tests and tools with several lose only
// the in-process shortcut. A DDS profiles file's <library_settings>, loaded after this, wins.
void use_interprocess_delivery_only() {
  static std::once_flag once;
  std::call_once(once, [] {
    auto settings = eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings();
    settings.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
    eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(settings);
  });
}

void use_localhost_only(DomainParticipantQos& qos) {
  // UDP on loopback only, no shared memory: a process killed with SIGKILL (a crash, the chaos
  // test) leaves Fast DDS 2.9's shared-memory ports in a state where restarted processes, and
  // sometimes running ones, no longer hear each other (upstream, still open in 2.14: a
  // restarted subscriber matches but receives nothing; a killed one breaks the others). It
  // shows as a restarted robot deaf to the safety stop naming it, or a restarted drill service
  // that never gets the latched model; over UDP every restart is heard (tests/system chaos).
  // Loopback UDP with 4 MiB socket buffers carries the 1.5 MB RGB + depth pairs at 15 Hz
  // without loss (bench_sensors_dds: 300 of 300 pairs, latency median 1.5 ms, vs 2.0 ms over
  // shared memory); with the kernel's default 208 KiB buffers two frames in three are lost.
  check_socket_buffer_limit();
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.emplace_back("127.0.0.1");
  udp->maxInitialPeersRange = kMaxLocalParticipants;
  udp->sendBufferSize = kSocketBufferBytes;
  udp->receiveBufferSize = kSocketBufferBytes;
  qos.transport().use_builtin_transports = false;
  qos.transport().user_transports.push_back(udp);

  eprosima::fastrtps::rtps::Locator_t local;
  local.kind = LOCATOR_KIND_UDPv4;
  eprosima::fastrtps::rtps::IPLocator::setIPv4(local, 127, 0, 0, 1);
  auto& builtin = qos.wire_protocol().builtin;
  builtin.initialPeersList.push_back(local);
  // A user-given metatraffic unicast locator keeps Fast DDS from adding its multicast one.
  builtin.metatrafficUnicastLocatorList.push_back(local);
  builtin.metatrafficMulticastLocatorList.clear();
  // No user-given default unicast locator: Fast DDS announces the whitelisted UDP 127.0.0.1 one.

  // Announce often: unicast announcements to 48 local ports cost nothing on loopback, and a
  // participant that starts late (a tool, a restarted service) is seen within half a second
  // instead of Fast DDS's 3 s; a participant that died is forgotten after 5 s, not 20 s.
  auto& discovery = builtin.discovery_config;
  discovery.initial_announcements.count = 10;
  discovery.initial_announcements.period = eprosima::fastrtps::Duration_t(0, 50'000'000);
  discovery.leaseDuration_announcementperiod = eprosima::fastrtps::Duration_t(0, 500'000'000);
  discovery.leaseDuration = eprosima::fastrtps::Duration_t(5, 0);
}

}  // namespace

void Participant::use_security(DomainParticipantQos& qos, const std::filesystem::path& pki,
                               const ParticipantOptions& options) {
  const std::string where = "CONCERT_SECURITY=" + pki.string();
  if (domain_id_ < security::kFirstDomain || domain_id_ > security::kLastDomain) {
    throw std::invalid_argument(where + ": domain " + std::to_string(domain_id_) +
                                " is outside the domains the PKI covers (" +
                                std::to_string(security::kFirstDomain) + " to " +
                                std::to_string(security::kLastDomain) + ")");
  }
  security_identity_ = security::resolve_identity(options.identity, options.name);
  security_dir_ = pki.string();
  const security::IdentityFiles files = security::identity_files(pki, security_identity_);
  try {
    security::check_identity(files);
  } catch (const std::exception& e) {
    throw std::runtime_error(where + ": " + e.what());
  }
  auto& properties = qos.properties().properties();
  for (auto& [name, value] : security::fastdds_properties(files)) properties.emplace_back(name, value);
}

Participant::Participant(ParticipantOptions options) : name_(options.name) {
  domain_id_ = options.domain_id >= 0 ? options.domain_id : domain_id_from_env();
  auto* factory = DomainParticipantFactory::get_instance();
  use_interprocess_delivery_only();

  DomainParticipantQos qos = PARTICIPANT_QOS_DEFAULT;
  std::string profiles = options.profiles_file;
  if (profiles.empty()) {
    if (const char* env = std::getenv("CONCERT_DDS_PROFILES")) profiles = env;
  }
  if (!profiles.empty()) {
    if (factory->load_XML_profiles_file(profiles) != ReturnCode_t::RETCODE_OK) {
      throw std::runtime_error("DDS profiles file '" + profiles + "' cannot be loaded (missing or invalid XML)");
    }
    if (factory->get_participant_qos_from_profile(options.profile_name, qos) != ReturnCode_t::RETCODE_OK) {
      throw std::runtime_error("DDS profiles file '" + profiles + "' has no participant profile '" +
                               options.profile_name + "'");
    }
  } else {
    std::string network = options.network;
    if (network.empty()) {
      const char* env = std::getenv("CONCERT_DDS_NETWORK");
      network = env != nullptr && *env != '\0' ? env : "localhost";
    }
    if (network == "localhost") {
      use_localhost_only(qos);
    } else if (network != "system") {
      throw std::invalid_argument("CONCERT_DDS_NETWORK: '" + network + "' is not 'localhost' or 'system'");
    }
  }
  qos.name(options.name);
  check_domain_ports(domain_id_);
  if (const auto pki = security::pki_from_environment()) {
    use_security(qos, *pki, options);
  }
  participant_ = factory->create_participant(domain_id_, qos, options.listener, StatusMask::none());
  if (participant_ == nullptr) {
    if (!security_identity_.empty()) {
      // Fast DDS logs no reason for a refused security setting; check_identity() ruled out
      // what it can name.
      throw std::runtime_error("cannot create a secured DDS participant as '" + security_identity_ +
                               "' on domain " + std::to_string(domain_id_) + " (CONCERT_SECURITY=" +
                               security_dir_ + "): Fast DDS refused its security settings");
    }
    throw std::runtime_error("cannot create a DDS participant on domain " + std::to_string(domain_id_));
  }
  publisher_ = participant_->create_publisher(PUBLISHER_QOS_DEFAULT);
  subscriber_ = participant_->create_subscriber(SUBSCRIBER_QOS_DEFAULT);
  if (publisher_ == nullptr || subscriber_ == nullptr) {
    factory->delete_participant(participant_);
    throw std::runtime_error("cannot create the DDS publisher/subscriber");
  }
}

Participant::~Participant() {
  participant_->delete_contained_entities();
  DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

Topic* Participant::topic(const std::string& name, TypeSupport type) {
  std::lock_guard lock(mutex_);
  const std::string type_name = type.get_type_name();
  TypeSupport registered = participant_->find_type(type_name);
  if (registered.empty()) {
    if (type.register_type(participant_) != ReturnCode_t::RETCODE_OK) {
      throw std::runtime_error("cannot register DDS type '" + type_name + "'");
    }
  }
  if (auto* existing = participant_->lookup_topicdescription(name)) {
    if (existing->get_type_name() != type_name) {
      throw std::runtime_error("topic '" + name + "' already exists with type '" + existing->get_type_name() +
                               "', not '" + type_name + "'");
    }
    return static_cast<Topic*>(existing);
  }
  Topic* topic = participant_->create_topic(name, type_name, TOPIC_QOS_DEFAULT);
  if (topic == nullptr) throw std::runtime_error("cannot create DDS topic '" + name + "'");
  return topic;
}

}  // namespace concert::dds
