#include "collab/voice.hpp"

#include <pocketsphinx.h>
#include <sndfile.h>
#include <soxr.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "collab/command_parser.hpp"

namespace concert::collab {
namespace {

const char* kGrammar =
    "#JSGF V1.0;\n"
    "grammar concert;\n"
    "public <command> = hey concert ( teaching | autonomous | follow me | stop | open | close | lift | place );\n";

struct Segment {
  std::string word;
  int sf{0};
  int ef{0};
  int32 ascr{0};
};

bool is_word(const std::string& w) { return !w.empty() && w[0] != '<' && w[0] != '[' && w != "(NULL)"; }

// The fraction of speech frames (10 ms, energy 10 dB above the recording's floor) that the
// grammar's alignment puts outside its words (silence, fillers): a sentence forced onto a
// command leaves most of its speech there.
double unexplained_speech(std::span<const std::int16_t> pcm, const std::vector<Segment>& segs) {
  constexpr std::size_t kFrame = 160;
  const std::size_t nf = pcm.size() / kFrame;
  if (nf == 0) return 0.0;
  std::vector<double> e(nf);
  for (std::size_t i = 0; i < nf; ++i) {
    double sum = 0;
    for (std::size_t j = 0; j < kFrame; ++j) sum += static_cast<double>(pcm[i * kFrame + j]) * pcm[i * kFrame + j];
    e[i] = sum / kFrame;
  }
  // The floor from the recording itself: frames of exact digital silence (the padding added
  // around an utterance) do not count.
  std::vector<double> sorted;
  for (double v : e)
    if (v > 0.0) sorted.push_back(v);
  if (sorted.empty()) return 0.0;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 10), sorted.end());
  const double threshold = std::max(10.0 * sorted[sorted.size() / 10], 1e4);  // +10 dB, and above -50 dBFS
  std::vector<bool> in_word(nf, false);
  for (const auto& s : segs)
    if (is_word(s.word))
      for (int f = std::max(0, s.sf); f <= s.ef && static_cast<std::size_t>(f) < nf; ++f) in_word[static_cast<std::size_t>(f)] = true;
  std::size_t speech = 0, outside = 0;
  for (std::size_t i = 0; i < nf; ++i)
    if (e[i] > threshold) {
      ++speech;
      if (!in_word[i]) ++outside;
    }
  return speech > 0 ? static_cast<double>(outside) / static_cast<double>(speech) : 0.0;
}

}  // namespace

struct VoiceRecognizer::Impl {
  cmd_ln_t* config{nullptr};
  ps_decoder_t* ps{nullptr};
  ~Impl() {
    if (ps != nullptr) ps_free(ps);
    if (config != nullptr) cmd_ln_free_r(config);
  }

  // Decodes with one search; the hypothesis, its path score and the segments.
  std::string decode(const char* search, std::span<const std::int16_t> pcm, int32& score, int& frames,
                     std::vector<Segment>& segs) {
    ps_set_search(ps, search);
    ps_start_utt(ps);
    ps_process_raw(ps, pcm.data(), pcm.size(), FALSE, TRUE);
    ps_end_utt(ps);
    score = 0;
    const char* hyp = ps_get_hyp(ps, &score);
    frames = ps_get_n_frames(ps);
    segs.clear();
    for (ps_seg_t* it = ps_seg_iter(ps); it != nullptr; it = ps_seg_next(it)) {
      Segment s;
      s.word = ps_seg_word(it);
      ps_seg_frames(it, &s.sf, &s.ef);
      int32 lscr = 0, lback = 0;
      ps_seg_prob(it, &s.ascr, &lscr, &lback);
      segs.push_back(std::move(s));
    }
    return hyp != nullptr ? hyp : "";
  }
};

VoiceRecognizer::VoiceRecognizer(VoiceParams params) : params_(std::move(params)), impl_(std::make_unique<Impl>()) {
  namespace fs = std::filesystem;
  const fs::path dir(params_.model_dir);
  const fs::path hmm = dir / "en-us";
  const fs::path dict = dir / "cmudict-en-us.dict";
  const fs::path phones = dir / "en-us-phone.lm.bin";
  for (const auto& p : {hmm / "mdef", dict, phones})
    if (!fs::exists(p))
      throw std::runtime_error("voice: model file " + p.string() + " is missing (Debian package pocketsphinx-en-us)");
  impl_->config = cmd_ln_init(nullptr, ps_args(), TRUE, "-hmm", hmm.c_str(), "-dict", dict.c_str(), "-logfn",
                              "/dev/null", "-allphone_ci", "yes", "-remove_silence", "no", "-dither", "yes", "-seed",
                              "1", nullptr);
  if (impl_->config == nullptr) throw std::runtime_error("voice: PocketSphinx refused its configuration");
  impl_->ps = ps_init(impl_->config);
  if (impl_->ps == nullptr) throw std::runtime_error("voice: PocketSphinx failed to load the model in " + dir.string());
  if (ps_set_jsgf_string(impl_->ps, "commands", kGrammar) != 0)
    throw std::runtime_error("voice: the command grammar did not compile");
  if (ps_set_allphone_file(impl_->ps, "phones", phones.c_str()) != 0)
    throw std::runtime_error("voice: the phone loop did not load from " + phones.string());
}

VoiceRecognizer::~VoiceRecognizer() = default;

Recognition VoiceRecognizer::recognise(std::span<const std::int16_t> pcm16k) {
  const auto t0 = std::chrono::steady_clock::now();
  Recognition out;
  // Silence around the utterance: the grammar's path must be able to end in silence.
  const auto pad = static_cast<std::size_t>(params_.pad_seconds * 16000.0);
  std::vector<std::int16_t> audio(pad, 0);
  audio.insert(audio.end(), pcm16k.begin(), pcm16k.end());
  audio.insert(audio.end(), pad, 0);

  int32 sg = 0, sp = 0;
  int frames = 0, frames_p = 0;
  std::vector<Segment> words, phones;
  out.hypothesis = impl_->decode("commands", audio, sg, frames, words);
  if (out.hypothesis.empty()) {
    out.reason = "no command fits the audio";
  } else {
    impl_->decode("phones", audio, sp, frames_p, phones);
    out.utterance_ratio = frames > 0 ? static_cast<double>(sg - sp) / frames : 0.0;
    // Each word's acoustic score against the phone loop's over the same frames (phones that
    // overlap the word count in proportion to the overlap).
    out.min_word_ratio = std::numeric_limits<double>::infinity();
    for (const auto& w : words) {
      if (!is_word(w.word)) continue;
      const int len = w.ef - w.sf + 1;
      if (len <= 0) continue;
      double loop = 0;
      for (const auto& p : phones) {
        const int a = std::max(p.sf, w.sf);
        const int b = std::min(p.ef, w.ef);
        if (b < a) continue;
        loop += static_cast<double>(p.ascr) * (b - a + 1) / (p.ef - p.sf + 1);
      }
      const double r = (static_cast<double>(w.ascr) - loop) / len;
      if (w.word.rfind("hey", 0) == 0 || w.word.rfind("concert", 0) == 0) out.wake_ratio = std::min(out.wake_ratio, r);
      if (r < out.min_word_ratio) {
        out.min_word_ratio = r;
        out.weakest_word = w.word;
      }
    }
    if (!std::isfinite(out.min_word_ratio)) out.min_word_ratio = 0;
    out.unexplained_speech = unexplained_speech(audio, words);
    const auto parsed = parse_command(out.hypothesis);
    if (!parsed.command) {
      out.reason = parsed.reason;
    } else if (out.utterance_ratio < params_.min_utterance_ratio) {
      out.reason = "not a command: the utterance fits free speech better (ratio " +
                   std::to_string(out.utterance_ratio) + " < " + std::to_string(params_.min_utterance_ratio) + ")";
    } else if (out.unexplained_speech > params_.max_unexplained_speech) {
      out.reason = "not a command: " + std::to_string(static_cast<int>(100 * out.unexplained_speech)) +
                   " % of the speech lies outside the command's words";
    } else if (out.wake_ratio < params_.min_wake_ratio) {
      out.reason = "not a command: the wake phrase fits poorly (ratio " + std::to_string(out.wake_ratio) + " < " +
                   std::to_string(params_.min_wake_ratio) + ")";
    } else if (out.min_word_ratio < params_.min_word_ratio) {
      out.reason = "not a command: \"" + out.weakest_word + "\" fits poorly (ratio " +
                   std::to_string(out.min_word_ratio) + " < " + std::to_string(params_.min_word_ratio) + ")";
    } else {
      out.command = parsed.command;
    }
  }
  out.decode_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

std::vector<std::int16_t> resample_to_16k(std::span<const float> samples, double rate) {
  if (!(rate >= 4000.0 && rate <= 384000.0))
    throw std::runtime_error("audio: sample rate " + std::to_string(rate) + " Hz is out of range");
  std::vector<float> out(static_cast<std::size_t>(std::ceil(static_cast<double>(samples.size()) * 16000.0 / rate)) + 16);
  std::size_t produced = 0;
  if (rate == 16000.0) {
    std::copy(samples.begin(), samples.end(), out.begin());
    produced = samples.size();
  } else {
    const soxr_error_t err = soxr_oneshot(rate, 16000.0, 1, samples.data(), samples.size(), nullptr, out.data(),
                                          out.size(), &produced, nullptr, nullptr, nullptr);
    if (err != nullptr) throw std::runtime_error(std::string("audio: resampling failed: ") + err);
  }
  std::vector<std::int16_t> pcm(produced);
  for (std::size_t i = 0; i < produced; ++i) {
    const float v = std::clamp(out[i], -1.0f, 1.0f) * 32767.0f;
    pcm[i] = static_cast<std::int16_t>(std::lround(v));
  }
  return pcm;
}

std::vector<std::int16_t> load_audio_16k(const std::string& path) {
  SF_INFO info{};
  SNDFILE* f = sf_open(path.c_str(), SFM_READ, &info);
  if (f == nullptr) throw std::runtime_error("audio file " + path + ": " + sf_strerror(nullptr));
  if (info.channels < 1 || info.frames <= 0) {
    sf_close(f);
    throw std::runtime_error("audio file " + path + ": no samples");
  }
  std::vector<float> inter(static_cast<std::size_t>(info.frames) * static_cast<std::size_t>(info.channels));
  const sf_count_t got = sf_readf_float(f, inter.data(), info.frames);
  sf_close(f);
  std::vector<float> mono(static_cast<std::size_t>(got));
  for (std::size_t i = 0; i < mono.size(); ++i) {
    float s = 0;
    for (int c = 0; c < info.channels; ++c) s += inter[i * static_cast<std::size_t>(info.channels) + static_cast<std::size_t>(c)];
    mono[i] = s / static_cast<float>(info.channels);
  }
  return resample_to_16k(mono, info.samplerate);
}

std::vector<std::vector<std::int16_t>> split_utterances(std::span<const std::int16_t> pcm, double factor,
                                                        double max_gap, double pad) {
  constexpr std::size_t kFrame = 160;  // 10 ms
  const std::size_t nf = pcm.size() / kFrame;
  std::vector<std::vector<std::int16_t>> out;
  if (nf == 0) return out;
  std::vector<double> rms(nf);
  for (std::size_t i = 0; i < nf; ++i) {
    double e = 0;
    for (std::size_t j = 0; j < kFrame; ++j) {
      const double v = pcm[i * kFrame + j];
      e += v * v;
    }
    rms[i] = std::sqrt(e / kFrame);
  }
  std::vector<double> sorted = rms;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(nf / 10), sorted.end());
  const double floor = sorted[nf / 10];
  const double threshold = std::max(factor * floor, 100.0);  // 100: about -50 dBFS
  const auto gap = static_cast<std::size_t>(max_gap * 100.0);
  const auto keep = static_cast<std::size_t>(pad * 100.0);
  std::size_t i = 0;
  while (i < nf) {
    if (rms[i] < threshold) {
      ++i;
      continue;
    }
    std::size_t end = i;
    std::size_t quiet = 0;
    for (std::size_t j = i; j < nf && quiet <= gap; ++j) {
      if (rms[j] >= threshold) {
        end = j;
        quiet = 0;
      } else {
        ++quiet;
      }
    }
    if (end - i + 1 >= 10) {  // at least 100 ms of speech
      const std::size_t a = i > keep ? i - keep : 0;
      const std::size_t b = std::min(nf, end + 1 + keep);
      out.emplace_back(pcm.begin() + static_cast<long>(a * kFrame), pcm.begin() + static_cast<long>(b * kFrame));
    }
    i = end + 1;
  }
  return out;
}

}  // namespace concert::collab
