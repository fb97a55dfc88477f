#pragma once
// Typed writer and reader over a catalogue topic, with the catalogue's QoS.

#include <algorithm>
#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include <set>

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "concert/dds/participant.hpp"
#include "concert/dds/qos.hpp"
#include "concert/dds/topics.hpp"

namespace concert::dds {

/// Why a secured participant may have been refused a writer (or reader) on `topic`, as text to
/// append to the error (": identity 'operator' may not publish it (only planner, nav, drill may;
/// CONCERT_SECURITY=DIR)"); empty when the participant is not secured.
std::string why_refused(const Participant& participant, std::string_view topic, bool writer);

namespace detail {
/// Which readers a writer has matched, by GUID, from its publication-matched events (Fast DDS
/// 2.9's DataWriter::get_matched_subscriptions answers RETCODE_UNSUPPORTED).
class MatchTracker : public eprosima::fastdds::dds::DataWriterListener {
 public:
  void on_publication_matched(eprosima::fastdds::dds::DataWriter* writer,
                              const eprosima::fastdds::dds::PublicationMatchedStatus& status) override;
  /// Whether a reader of the participant `prefix` names is matched now.
  bool matched_participant(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix) const;

 private:
  mutable std::mutex mutex_;
  std::set<eprosima::fastrtps::rtps::GUID_t> readers_;
};

/// Checks `name` against the catalogue (exists, type name matches) and creates the writer
/// (with `tracker` listening to its matches, when given).
eprosima::fastdds::dds::DataWriter* create_writer(Participant& participant, std::string_view name,
                                                  eprosima::fastdds::dds::TypeSupport type,
                                                  MatchTracker* tracker = nullptr);
eprosima::fastdds::dds::DataReader* create_reader(Participant& participant, std::string_view name,
                                                  eprosima::fastdds::dds::TypeSupport type,
                                                  eprosima::fastdds::dds::DataReaderListener* listener);
void delete_writer(Participant& participant, eprosima::fastdds::dds::DataWriter* writer);
void delete_reader(Participant& participant, eprosima::fastdds::dds::DataReader* reader);
bool wait_until(const std::function<bool()>& done, std::chrono::milliseconds timeout);
/// Readers matched to `writer` now.
int32_t matched_count(eprosima::fastdds::dds::DataWriter* writer);
/// Writers matched to `reader` now.
int32_t matched_count(eprosima::fastdds::dds::DataReader* reader);

/// Takes samples from `reader` until a valid one (left in `sample` and `info`); false when none
/// is left.
template <class T>
bool take_valid(eprosima::fastdds::dds::DataReader* reader, T& sample,
                eprosima::fastdds::dds::SampleInfo& info) {
  while (reader->take_next_sample(&sample, &info) ==
         eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    if (info.valid_data) return true;
  }
  return false;
}
}  // namespace detail

/// Writer option: remember which readers matched (Writer::matched_participant).
enum class TrackMatches { kNo, kYes };

template <class T> class Writer {
 public:
  Writer(Participant& participant, TopicHandle<T> topic, TrackMatches track = TrackMatches::kNo)
      : participant_(participant),
        tracker_(track == TrackMatches::kYes ? std::make_unique<detail::MatchTracker>() : nullptr),
        writer_(detail::create_writer(participant, topic.name,
                                      eprosima::fastdds::dds::TypeSupport(new typename PubSubOf<T>::type()),
                                      tracker_.get())) {}
  ~Writer() { detail::delete_writer(participant_, writer_); }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Publishes a sample. Returns false if DDS refused it (e.g. while shutting down). On a keyed
  /// topic a sample of a new instance unregisters the oldest one once kLiveInstances are live
  /// (late joiners then get the newest kLiveInstances instances' last samples).
  bool write(const T& sample) {
    if (!keyed_) return writer_->write(const_cast<T*>(&sample));
    std::lock_guard lock(instances_mutex_);
    const eprosima::fastrtps::rtps::InstanceHandle_t handle =
        writer_->register_instance(const_cast<T*>(&sample));
    if (handle == eprosima::fastdds::dds::HANDLE_NIL) return false;
    const bool known = std::any_of(live_.begin(), live_.end(),
                                   [&](const auto& entry) { return entry.first == handle; });
    if (!known) {
      live_.emplace_back(handle, sample);
      if (live_.size() > kLiveInstances) {
        writer_->unregister_instance(&live_.front().second, live_.front().first);
        live_.pop_front();
      }
    }
    return writer_->write(const_cast<T*>(&sample), handle) ==
           eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
  }

  /// Disposes the instance `sample` names (keyed topics only).
  bool dispose(const T& sample) {
    return writer_->dispose(const_cast<T*>(&sample), eprosima::fastdds::dds::HANDLE_NIL) ==
           eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
  }

  int32_t matched_readers() const { return detail::matched_count(writer_); }

  /// Whether a reader of the participant `prefix` names is matched now (TrackMatches::kYes
  /// only; false otherwise). A tool that must reach one service, not any reader of the topic,
  /// waits for this.
  bool matched_participant(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix) const {
    return tracker_ != nullptr && tracker_->matched_participant(prefix);
  }

  /// Waits until at least `count` readers matched; false on timeout.
  bool wait_for_readers(int32_t count, std::chrono::milliseconds timeout) const {
    return detail::wait_until([&] { return matched_readers() >= count; }, timeout);
  }

  eprosima::fastdds::dds::DataWriter* get() const { return writer_; }

 private:
  Participant& participant_;
  std::unique_ptr<detail::MatchTracker> tracker_;  // before writer_: it listens from creation
  eprosima::fastdds::dds::DataWriter* writer_;
  bool keyed_ = writer_->get_type()->m_isGetKeyDefined;
  std::mutex instances_mutex_;
  // Registered instances, oldest first, with a sample carrying each one's key.
  std::deque<std::pair<eprosima::fastrtps::rtps::InstanceHandle_t, T>> live_;
};

/// Reads a catalogue topic. With a callback, every valid sample is handed to it on the DDS
/// listener thread (keep it short; never throw out of it). Without, poll with take()/wait().
template <class T> class Reader : private eprosima::fastdds::dds::DataReaderListener {
 public:
  using Callback = std::function<void(const T&, const eprosima::fastdds::dds::SampleInfo&)>;

  Reader(Participant& participant, TopicHandle<T> topic, Callback callback = {})
      : participant_(participant), callback_(std::move(callback)) {
    reader_ = detail::create_reader(participant, topic.name,
                                    eprosima::fastdds::dds::TypeSupport(new typename PubSubOf<T>::type()),
                                    callback_ ? this : nullptr);
  }
  ~Reader() override { detail::delete_reader(participant_, reader_); }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  /// The next unread valid sample, if any.
  std::optional<T> take() {
    T sample;
    eprosima::fastdds::dds::SampleInfo info;
    if (detail::take_valid(reader_, sample, info)) return sample;
    return std::nullopt;
  }

  /// Waits up to `timeout` for the next valid sample.
  std::optional<T> wait(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      if (auto s = take()) return s;
      const auto left = deadline - std::chrono::steady_clock::now();
      if (left <= std::chrono::nanoseconds::zero()) return std::nullopt;
      const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(left).count();
      reader_->wait_for_unread_message(eprosima::fastrtps::Duration_t(
          static_cast<int32_t>(ns / 1'000'000'000), static_cast<uint32_t>(ns % 1'000'000'000)));
    }
  }

  int32_t matched_writers() const { return detail::matched_count(reader_); }

  bool wait_for_writers(int32_t count, std::chrono::milliseconds timeout) const {
    return detail::wait_until([&] { return matched_writers() >= count; }, timeout);
  }

  eprosima::fastdds::dds::DataReader* get() const { return reader_; }

 private:
  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
    T sample;
    eprosima::fastdds::dds::SampleInfo info;
    while (detail::take_valid(reader, sample, info)) callback_(sample, info);
  }

  Participant& participant_;
  Callback callback_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
};

}  // namespace concert::dds
