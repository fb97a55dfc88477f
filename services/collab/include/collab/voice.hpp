#pragma once
// Offline voice commands (paper section 5.5: "Hey CONCERT, <command>") with PocketSphinx
// (Debian's libpocketsphinx-dev, US-English model pocketsphinx-en-us). Plain C++; no DDS.
//
// A JSGF grammar ("hey concert" + one of the eight commands) recognises commands well but maps
// every sound onto some command. Rejection: the same audio is decoded a second time by an
// unconstrained phone loop (PocketSphinx's allphone search); speech that is not a command fits
// the phone loop much better than the grammar. Two tests, thresholds calibrated on synthesised
// speech (README, "Voice"): the whole utterance's score ratio per frame, and the weakest word's
// acoustic ratio per frame (a sentence forced onto "hey concert stop" has one badly fitting
// word), the same for the wake phrase's two words, and the share of the speech (by energy) that
// the grammar's alignment leaves in silence between and around its words (a long sentence
// forced onto three words leaves most of itself there). The accepted text then goes through parse_command like the typed path.

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "collab/state_machine.hpp"

namespace concert::collab {

struct VoiceParams {
  std::string model_dir{"/usr/share/pocketsphinx/model/en-us"};  ///< en-us/, cmudict-en-us.dict, en-us-phone.lm.bin
  // Thresholds calibrated on the synthesised set of voice_test (README, "Voice").
  double min_utterance_ratio{0.0};  ///< grammar vs phone loop, path score per frame
  double min_word_ratio{-90.0};     ///< the weakest word's acoustic score vs phone loop, per frame
  double min_wake_ratio{-44.0};     ///< the same for the weaker of "hey" and "concert"
  double max_unexplained_speech{0.12};  ///< speech frames the alignment leaves outside the words
  double pad_seconds{0.3};          ///< silence added before and after an utterance
};

struct Recognition {
  std::string hypothesis;   ///< the grammar's text ("hey concert lift"), empty when nothing fitted
  std::optional<Command> command;  ///< set when accepted
  std::string reason;       ///< why rejected
  double utterance_ratio{0.0};
  double min_word_ratio{0.0};
  std::string weakest_word;
  double wake_ratio{0.0};  // 0 when no word fitted  ///< the weaker of "hey" and "concert", same units as min_word_ratio
  double unexplained_speech{0.0};  ///< fraction of speech frames outside the command's words
  double decode_ms{0.0};
};

/// One decoder (loading the model takes 0.1-0.5 s: build it once). Not thread-safe.
class VoiceRecognizer {
 public:
  /// Throws std::runtime_error naming the missing model file.
  explicit VoiceRecognizer(VoiceParams params = {});
  ~VoiceRecognizer();
  VoiceRecognizer(const VoiceRecognizer&) = delete;
  VoiceRecognizer& operator=(const VoiceRecognizer&) = delete;

  /// One utterance of 16 kHz mono 16-bit audio.
  Recognition recognise(std::span<const std::int16_t> pcm16k);

  const VoiceParams& params() const { return params_; }

 private:
  struct Impl;
  VoiceParams params_;
  std::unique_ptr<Impl> impl_;
};

/// Reads a WAV (or any format libsndfile reads), mixes to mono and resamples to 16 kHz (soxr).
/// Throws std::runtime_error naming the file and the problem.
std::vector<std::int16_t> load_audio_16k(const std::string& path);

/// Resamples mono float samples in [-1, 1] at `rate` Hz to 16 kHz 16-bit.
std::vector<std::int16_t> resample_to_16k(std::span<const float> samples, double rate);

/// Splits a recording into utterances by short-time energy: speech is a 10 ms frame above
/// `factor` times the noise floor (the 10th percentile) and above an absolute floor; pauses
/// shorter than `max_gap` seconds stay inside an utterance. Each piece keeps `pad` seconds
/// of the surrounding audio.
std::vector<std::vector<std::int16_t>> split_utterances(std::span<const std::int16_t> pcm16k, double factor = 3.0,
                                                        double max_gap = 0.5, double pad = 0.25);

}  // namespace concert::collab
