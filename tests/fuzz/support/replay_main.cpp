// The main of a fuzz target in the normal build: runs LLVMFuzzerTestOneInput on every file
// given (folders: every file below them, sorted), so seeds and regression inputs stay tested
// without clang. A crash or a failed CONCERT_FUZZ_CHECK aborts, which fails the ctest.
//   fuzz_x SEED_DIR... [--regressions DIR]   (the regression folder may be absent or empty)
//   fuzz_x --write-seeds DIR
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz.hpp"

namespace fs = std::filesystem;

namespace {

std::vector<fs::path> files_below(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

size_t run_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    std::cerr << file.string() << ": cannot read\n";
    std::exit(1);
  }
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  (void)LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (concert::fuzz::handle_write_seeds(argc, argv)) return 0;
  const std::string name = fs::path(argv[0]).filename().string();
  size_t seeds = 0;
  size_t regressions = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--regressions") {
      if (++i == argc) {
        std::cerr << name << ": --regressions needs a folder\n";
        return 2;
      }
      if (!fs::is_directory(argv[i])) continue;  // no crash recorded for this target yet
      for (const fs::path& f : files_below(argv[i])) regressions += run_file(f);
      continue;
    }
    if (fs::is_regular_file(arg)) {
      seeds += run_file(arg);
      continue;
    }
    if (!fs::is_directory(arg)) {
      std::cerr << name << ": " << arg << ": no such file or folder\n";
      return 2;
    }
    const std::vector<fs::path> files = files_below(arg);
    if (files.empty()) {
      std::cerr << name << ": " << arg << ": no input in the folder\n";
      return 1;
    }
    for (const fs::path& f : files) seeds += run_file(f);
  }
  if (seeds == 0) {
    std::cerr << name << ": no seed input given (usage: " << name
              << " SEED_DIR... [--regressions DIR] | --write-seeds DIR)\n";
    return 2;
  }
  std::cout << name << ": " << seeds << " seed and " << regressions
            << " regression inputs ran without a crash\n";
  return 0;
}
