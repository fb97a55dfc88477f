#pragma once
// Speech synthesised at test time with espeak-ng (several voices and speeds), and seeded white
// noise at a given SNR, for the voice tests and the voice benchmark.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "collab/voice.hpp"

namespace concert::collab::test {

struct Voice {
  std::string name;
  int speed;
};

inline const std::vector<Voice>& voices() {
  static const std::vector<Voice> v{{"en-us", 150}, {"en-gb", 170}, {"en-us+f3", 140}, {"en-gb-scotland", 160}};
  return v;
}

/// espeak-ng into a WAV in `dir`, read back at 16 kHz. Throws with espeak-ng's exit code.
inline std::vector<std::int16_t> synthesise(const std::filesystem::path& dir, const std::string& text,
                                            const Voice& voice, int index) {
  const auto wav = dir / ("u" + std::to_string(index) + ".wav");
  const std::string cmd = "espeak-ng -v '" + voice.name + "' -s " + std::to_string(voice.speed) + " -w '" +
                          wav.string() + "' '" + text + "' 2>/dev/null";
  const int rc = std::system(cmd.c_str());
  if (rc != 0) throw std::runtime_error("espeak-ng failed (" + std::to_string(rc) + "): " + cmd);
  return load_audio_16k(wav.string());
}

/// White Gaussian noise at `snr_db` relative to the speech's power (frames above -50 dBFS).
inline std::vector<std::int16_t> add_noise(const std::vector<std::int16_t>& pcm, double snr_db, unsigned seed) {
  double power = 0;
  std::size_t n = 0;
  for (auto s : pcm)
    if (std::abs(s) > 100) {
      power += static_cast<double>(s) * s;
      ++n;
    }
  power = n > 0 ? power / static_cast<double>(n) : 0.0;
  const double sigma = std::sqrt(power / std::pow(10.0, snr_db / 10.0));
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  // Noise also before and after the speech (a real room is never silent).
  std::vector<std::int16_t> out(pcm.size() + 9600);
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double s = (i >= 4800 && i - 4800 < pcm.size()) ? pcm[i - 4800] : 0.0;
    out[i] = static_cast<std::int16_t>(std::clamp(s + noise(rng), -32768.0, 32767.0));
  }
  return out;
}

inline const std::vector<std::string>& non_commands() {
  static const std::vector<std::string> s{
      "please stop the music in the kitchen",
      "can you lift that heavy box for me",
      "I will follow you to the office",
      "the concert starts at eight tonight",
      "hey, close the door when you leave",
      "we should place the beam near the wall",
      "the car is fully autonomous",
      "hey there, how are you doing today",
      "follow me",
      "open",
      "where did you put the hammer",
      "the weather is nice this morning",
  };
  return s;
}

}  // namespace concert::collab::test
