#include "concert/common/text.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace concert {

std::vector<std::string> split(std::string_view text, char separator) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find(separator, start), text.size());
    if (end > start) out.emplace_back(text.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

std::string read_file(const std::filesystem::path& file, std::string_view what) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    throw std::runtime_error(std::string(what) + " file '" + file.string() + "' cannot be opened");
  }
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace concert
