#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

#include "concert/common/error_text.hpp"
#include "concert/common/source_text.hpp"

namespace concert {
namespace {

class ReadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

TEST(ErrorText, GivesTheMessageOfTheNamedErrorOnly) {
  EXPECT_EQ(error_text<ReadError>([] { throw ReadError("a.yaml: x: missing"); }),
            "a.yaml: x: missing");
  EXPECT_EQ(error_text<ReadError>([] {}), "(no error)");
  EXPECT_EQ(error_text<ReadError>([] {}, ""), "");
  EXPECT_THROW((void)error_text<ReadError>([] { throw std::logic_error("other"); }),
               std::logic_error);
}

TEST(SourceText, ReadsAWholeFileOrNamesIt) {
  const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                     ("concert_source_text_" + std::to_string(::getpid()));
  {
    std::ofstream out(file);
    out << "a: 1\nb: [2, 3]\n";
  }
  EXPECT_EQ(read_text<ReadError>(file, "the test file"), "a: 1\nb: [2, 3]\n");
  std::filesystem::remove(file);
  EXPECT_EQ(error_text<ReadError>([&] { (void)read_text<ReadError>(file, "the test file"); }),
            file.string() + ": cannot open the test file");
}

TEST(SourceText, ParsesYamlOrSaysWhereItCameFrom) {
  const YAML::Node root = parse_yaml<ReadError>("a: 1\nb: [2, 3]\n", "inline");
  EXPECT_EQ(root["a"].as<int>(), 1);
  EXPECT_EQ(root["b"].size(), 2u);
  const std::string error =
      error_text<ReadError>([] { (void)parse_yaml<ReadError>("b: [2, 3\n", "bad.yaml"); });
  EXPECT_EQ(error.rfind("bad.yaml: not valid YAML: ", 0), 0u) << error;
}

}  // namespace
}  // namespace concert
