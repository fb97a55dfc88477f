#pragma once
// What every fuzz target (tests/fuzz/fuzz_*.cpp) shares. A target defines
//
//   extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);  // one input
//   void concert::fuzz::write_seeds(SeedWriter& seeds);  // its seed corpus and dictionary
//
// and is linked either with libFuzzer (clang, -DCONCERT_FUZZ=ON: `make fuzz`) or with the replay
// main of replay_main.cpp (the normal build: a ctest runs every seed and regression input).
// Both mains answer `--write-seeds DIR`, which writes the target's seeds into DIR and its
// dictionary into DIR.dict (the build does it after linking). See tests/fuzz/README.md.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <string_view>
#include <vector>

/// Checks a property of the code under test; on failure prints where and what, then aborts, so
/// that libFuzzer records the input as a crash and the replay test fails.
#define CONCERT_FUZZ_CHECK(condition, message)                                                  \
  do {                                                                                          \
    if (!(condition)) ::concert::fuzz::check_failed(__FILE__, __LINE__, #condition, (message)); \
  } while (false)

namespace concert::fuzz {

[[noreturn]] void check_failed(const char* file, int line, const char* condition,
                               const std::string& message);

/// The input as text (it may hold any byte, NUL included).
inline std::string_view text_of(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// The parts of `input` separated by `separator`, at most `max_parts` (the last part keeps the
/// rest, separators included).
std::vector<std::string_view> split(std::string_view input, char separator, size_t max_parts);

/// True if `text` is valid UTF-8 (what JSON and YAML text must be).
bool valid_utf8(std::string_view text);

/// A file holding `content`, named `name` in a private temporary folder of this process (for
/// parsers that only read files, e.g. the module database loaders; the file name matters to
/// them: a module's key is its file's stem). Rewritten on each call.
std::filesystem::path input_file(const std::string& name, std::string_view content);

/// Where the repository's and the shared data's real files are (CONCERT_SOURCE_DIR,
/// CONCERT_SHARED_DATA compiled in).
std::filesystem::path source_dir();
std::filesystem::path shared_data_dir();

/// The repository's assembly files (libs/simbus/examples, deploy/demo), sorted.
std::vector<std::filesystem::path> assembly_files();

/// Syntax tokens for dictionaries.
extern const std::vector<std::string> kYamlTokens;
extern const std::vector<std::string> kJsonTokens;
extern const std::vector<std::string> kXmlTokens;

/// Writes a seed corpus (one file per seed) and its libFuzzer dictionary.
class SeedWriter {
 public:
  explicit SeedWriter(std::filesystem::path dir);

  /// A seed with the given file name and content.
  void add(const std::string& name, std::string_view content);
  /// A copy of a real file; its name is its path below `root` with '/' turned into '_'.
  void add_file(const std::filesystem::path& file, const std::filesystem::path& root);
  /// Every file below `root` whose name ends in `suffix`, in sorted order; throws
  /// std::runtime_error when there is none (a seed corpus never silently shrinks to nothing).
  void add_files(const std::filesystem::path& root, std::string_view suffix);
  /// Dictionary entries.
  void add_tokens(const std::vector<std::string>& tokens);
  /// Also put every word of the seeds (identifier-like, 3 to 40 characters) into the dictionary.
  void words_from_seeds(bool on) { words_ = on; }

  /// Writes the dictionary next to the folder (DIR.dict); returns the number of seeds.
  size_t finish();

 private:
  std::filesystem::path dir_;
  std::set<std::string> tokens_;
  std::set<std::string> names_;
  bool words_ = true;
  size_t count_ = 0;
};

/// Defined by each target.
void write_seeds(SeedWriter& seeds);

/// Handles `--write-seeds DIR` for both mains: writes and returns true if asked to.
bool handle_write_seeds(int argc, char** argv);

}  // namespace concert::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
