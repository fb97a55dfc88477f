#include "fuzz.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "concert/common/text.hpp"

namespace concert::fuzz {

namespace fs = std::filesystem;

void check_failed(const char* file, int line, const char* condition, const std::string& message) {
  std::fprintf(stderr, "%s:%d: fuzz check failed: %s\n  %s\n", file, line, condition,
               message.c_str());
  std::fflush(stderr);
  std::abort();
}

std::vector<std::string_view> split(std::string_view input, char separator, size_t max_parts) {
  std::vector<std::string_view> parts;
  while (parts.size() + 1 < max_parts) {
    const size_t at = input.find(separator);
    if (at == std::string_view::npos) break;
    parts.push_back(input.substr(0, at));
    input.remove_prefix(at + 1);
  }
  parts.push_back(input);
  return parts;
}

namespace {

fs::path private_temp_dir() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() / ("concert-fuzz-" + std::to_string(::getpid()));
    fs::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(fs::temp_directory_path() / ("concert-fuzz-" + std::to_string(::getpid())),
                     ec);
    });
    return d;
  }();
  return dir;
}

void write_file(const fs::path& file, std::string_view content) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(content.data(), static_cast<std::streamsize>(content.size()));
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
}

/// A dictionary entry in libFuzzer's syntax: "text" with \\, \" and \xNN escapes.
std::string dict_entry(std::string_view token) {
  static const char* hex = "0123456789ABCDEF";
  std::string out = "\"";
  for (const char c : token) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\\' || c == '"') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u >= 0x7f) {
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 0xf];
    } else {
      out += c;
    }
  }
  return out + "\"";
}

bool word_char(char c, bool first) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' ||
         (!first && c >= '0' && c <= '9');
}

}  // namespace

bool valid_utf8(std::string_view text) { return !invalid_utf8_at(text); }

fs::path input_file(const std::string& name, std::string_view content) {
  const fs::path file = private_temp_dir() / name;
  write_file(file, content);
  return file;
}

fs::path source_dir() { return CONCERT_SOURCE_DIR; }

std::vector<fs::path> assembly_files() {
  std::vector<fs::path> files;
  for (const fs::path& dir :
       {source_dir() / "libs/simbus/examples", source_dir() / "deploy/demo"}) {
    for (const auto& entry : fs::directory_iterator(dir)) {
      const std::string name = entry.path().filename().string();
      const bool other = name.find("_site") != std::string::npos ||
                         name.find("_mission") != std::string::npos;  // worlds, missions
      if (entry.path().extension() == ".yaml" && !other) files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}
fs::path shared_data_dir() { return CONCERT_SHARED_DATA; }

const std::vector<std::string> kYamlTokens = {": ",
                                              "- ",
                                              "-",
                                              "{",
                                              "}",
                                              "[",
                                              "]",
                                              ", ",
                                              "\n",
                                              "\n  ",
                                              "\n  - ",
                                              "---\n",
                                              "...\n",
                                              "#",
                                              "&a ",
                                              "*a",
                                              "<<: ",
                                              "!!str ",
                                              "!!int ",
                                              "!!map",
                                              "!!seq",
                                              "? ",
                                              "|\n",
                                              ">\n",
                                              "\"",
                                              "'",
                                              "~",
                                              "null",
                                              "true",
                                              "false",
                                              "yes",
                                              "no",
                                              ".inf",
                                              "-.inf",
                                              ".nan",
                                              "0x",
                                              "0o",
                                              "1e9",
                                              "-1",
                                              "0",
                                              "2147483648",
                                              "-2147483649",
                                              "9223372036854775808",
                                              "1e400"};
const std::vector<std::string> kJsonTokens = {
    "{",        "}",     "[",          "]",           ":",
    ",",        "\"",    "\\u0000",    "\\\"",        "null",
    "true",     "false", "-",          "1e308",       "1e400",
    "-0",       "0.5",   "2147483648", "-2147483649", "18446744073709551616",
    "Infinity", "NaN"};
const std::vector<std::string> kXmlTokens = {"<",
                                             ">",
                                             "</",
                                             "/>",
                                             "=\"",
                                             "\"",
                                             "<?xml version=\"1.0\"?>",
                                             "<!--",
                                             "-->",
                                             "<![CDATA[",
                                             "]]>",
                                             "&amp;",
                                             "&lt;",
                                             "&#x41;",
                                             "<robot name=\"r\">",
                                             "</robot>",
                                             "<link name=\"",
                                             "<joint name=\"",
                                             "type=\"revolute\"",
                                             "type=\"continuous\"",
                                             "type=\"prismatic\"",
                                             "type=\"fixed\"",
                                             "type=\"floating\"",
                                             "type=\"planar\"",
                                             "<parent link=\"",
                                             "<child link=\"",
                                             "<origin xyz=\"",
                                             "rpy=\"",
                                             "<axis xyz=\"",
                                             "<limit ",
                                             "lower=\"",
                                             "upper=\"",
                                             "effort=\"",
                                             "velocity=\"",
                                             "<inertial>",
                                             "<mass value=\"",
                                             "<inertia ",
                                             "ixx=\"",
                                             "<collision>",
                                             "<visual>",
                                             "<geometry>",
                                             "<box size=\"",
                                             "<cylinder radius=\"",
                                             "length=\"",
                                             "<sphere radius=\"",
                                             "<mesh filename=\"",
                                             "scale=\"",
                                             "<disable_collisions ",
                                             "link1=\"",
                                             "link2=\"",
                                             "nan",
                                             "inf",
                                             "-1e308",
                                             "0 0 0",
                                             "1 0 0"};

SeedWriter::SeedWriter(fs::path dir) : dir_(std::move(dir)) {
  std::error_code ec;
  fs::remove_all(dir_, ec);
  fs::create_directories(dir_);
}

void SeedWriter::add(const std::string& name, std::string_view content) {
  if (!names_.insert(name).second) throw std::runtime_error("seed '" + name + "' written twice");
  write_file(dir_ / name, content);
  ++count_;
  if (!words_) return;
  for (size_t i = 0; i < content.size();) {
    if (!word_char(content[i], true)) {
      ++i;
      continue;
    }
    size_t end = i + 1;
    while (end < content.size() && word_char(content[end], false)) ++end;
    if (end - i >= 3 && end - i <= 40) tokens_.insert(std::string(content.substr(i, end - i)));
    i = end;
  }
}

void SeedWriter::add_file(const fs::path& file, const fs::path& root) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.string() + ": cannot read");
  const std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string name = fs::relative(file, root).generic_string();
  std::replace(name.begin(), name.end(), '/', '_');
  add(name, content);
}

void SeedWriter::add_files(const fs::path& root, std::string_view suffix) {
  std::vector<fs::path> files;
  if (fs::is_directory(root)) {
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
      const std::string name = entry.path().filename().string();
      if (entry.is_regular_file() && name.size() >= suffix.size() &&
          name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
        files.push_back(entry.path());
      }
    }
  }
  if (files.empty()) {
    throw std::runtime_error(root.string() + ": no *" + std::string(suffix) +
                             " file for the seeds");
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files) add_file(f, root.parent_path());
}

void SeedWriter::add_tokens(const std::vector<std::string>& tokens) {
  tokens_.insert(tokens.begin(), tokens.end());
}

size_t SeedWriter::finish() {
  if (count_ == 0) throw std::runtime_error(dir_.string() + ": no seeds");
  std::ofstream dict(dir_.string() + ".dict", std::ios::trunc);
  dict << "# Generated by --write-seeds: syntax tokens of the format and words of the seeds.\n";
  for (const std::string& t : tokens_) {
    if (!t.empty() && t.size() <= 64) dict << dict_entry(t) << "\n";
  }
  if (!dict) throw std::runtime_error(dir_.string() + ".dict: cannot write");
  return count_;
}

bool handle_write_seeds(int argc, char** argv) {
  if (argc < 2 || std::string_view(argv[1]) != "--write-seeds") return false;
  if (argc != 3) {
    std::cerr << argv[0] << ": usage: --write-seeds DIR\n";
    std::exit(2);
  }
  try {
    SeedWriter seeds(argv[2]);
    write_seeds(seeds);
    const size_t n = seeds.finish();
    std::cout << fs::path(argv[0]).filename().string() << ": " << n << " seeds in " << argv[2]
              << "\n";
  } catch (const std::exception& e) {
    std::cerr << argv[0] << ": writing the seeds: " << e.what() << "\n";
    std::exit(1);
  }
  return true;
}

}  // namespace concert::fuzz
