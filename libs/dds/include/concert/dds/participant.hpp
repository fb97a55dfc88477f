#pragma once
// A Fast DDS domain participant with one publisher and one subscriber, configured from the
// environment (CONCERT_DOMAIN_ID) and optionally an XML profile (deploy/dds/); secured (DDS
// Security: authentication, access control, encryption) when CONCERT_SECURITY names a PKI folder
// made by `concert security init` (libs/security).

#include <filesystem>
#include <memory>
#include <mutex>
#include <string>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "concert/dds/catalogue.hpp"

namespace concert::dds {

/// Send and receive socket buffer of the "localhost" network's UDP transport [bytes]. A sample
/// is sent as <= 64 KB fragments in one burst; a 640x480 RGB8 image (921,600 bytes) plus its
/// depth image overflow the kernel's default 208 KiB receive buffer (bench_sensors_dds lost two
/// frames in three). The kernel caps the request at net.core.rmem_max / wmem_max
/// (deploy/install-deps.sh raises them; a participant warns once when they are lower).
inline constexpr uint32_t kSocketBufferBytes = 4u * 1024u * 1024u;

struct ParticipantOptions {
  std::string name = "concert";   ///< participant name, shown by DDS tools
  int32_t domain_id = -1;         ///< -1: CONCERT_DOMAIN_ID (default 0)
  /// Fast DDS XML profiles file; empty: CONCERT_DDS_PROFILES if set, else built-in defaults.
  std::string profiles_file;
  std::string profile_name = "concert_participant";  ///< participant profile in that file
  /// Without a profile: "localhost" (default; UDP on 127.0.0.1, no shared memory, unicast
  /// discovery, nothing leaves the machine) or "system" (Fast DDS defaults: every interface,
  /// multicast discovery). Empty: CONCERT_DDS_NETWORK if set, else "localhost".
  std::string network;
  /// Optional listener for discovery events (participants, writers, readers on the domain).
  eprosima::fastdds::dds::DomainParticipantListener* listener = nullptr;
  /// The security identity when CONCERT_SECURITY is set (its files are
  /// $CONCERT_SECURITY/<identity>/). Empty: the name when it is a service's ("robot"), else
  /// CONCERT_SECURITY_IDENTITY if set, else "operator" (security::resolve_identity).
  std::string identity;
};

/// Owns a DomainParticipant. Writers and readers made from it must be destroyed before it.
class Participant {
 public:
  /// Throws std::runtime_error (or std::invalid_argument for a bad domain id) with the reason;
  /// when secured, also for an identity whose files are missing, expired or do not verify
  /// against the PKI's CA (naming the file).
  explicit Participant(ParticipantOptions options = {});
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  int32_t domain_id() const { return domain_id_; }
  const std::string& name() const { return name_; }
  /// The security identity this participant authenticated as; empty when not secured.
  const std::string& security_identity() const { return security_identity_; }
  /// The PKI folder (CONCERT_SECURITY) when secured; empty otherwise.
  const std::string& security_dir() const { return security_dir_; }
  eprosima::fastdds::dds::DomainParticipant* get() const { return participant_; }
  eprosima::fastdds::dds::Publisher* publisher() const { return publisher_; }
  eprosima::fastdds::dds::Subscriber* subscriber() const { return subscriber_; }

  /// The topic `name` with type `type` (registered on first use). Throws if the topic exists
  /// with another type.
  eprosima::fastdds::dds::Topic* topic(const std::string& name, eprosima::fastdds::dds::TypeSupport type);

 private:
  /// Turns DDS Security on in `qos` with the identity `options` resolve to in `pki`.
  void use_security(eprosima::fastdds::dds::DomainParticipantQos& qos, const std::filesystem::path& pki,
                    const ParticipantOptions& options);

  std::string name_;
  std::string security_identity_;
  std::string security_dir_;
  int32_t domain_id_ = 0;
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  std::mutex mutex_;
};

}  // namespace concert::dds
