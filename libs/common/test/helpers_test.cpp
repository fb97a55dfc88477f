#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>

#include "concert/common/command_once.hpp"
#include "concert/common/error_text.hpp"
#include "concert/common/priority.hpp"
#include "concert/common/resend.hpp"
#include "concert/common/source_text.hpp"

namespace concert {
namespace {

class ReadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

TEST(ThreadNice, SetsTheCallingThreadOnlyAndSaysWhenItMayNot) {
  const auto nice_of_this_thread = [] { return getpriority(PRIO_PROCESS, static_cast<id_t>(::gettid())); };
  const int main_before = nice_of_this_thread();
  NiceResult up, down;
  int up_seen = 0;
  std::thread([&] {
    up = set_thread_nice(main_before + 3);  // a higher nice value is always allowed
    up_seen = nice_of_this_thread();
    down = set_thread_nice(main_before - 2);  // lower: only with CAP_SYS_NICE or RLIMIT_NICE
  }).join();
  EXPECT_TRUE(up.applied) << up.error;
  EXPECT_EQ(up.now, main_before + 3);
  EXPECT_EQ(up_seen, main_before + 3);
  if (down.applied) {
    EXPECT_EQ(down.now, main_before - 2);
    EXPECT_TRUE(down.error.empty());
  } else {
    EXPECT_EQ(down.now, main_before + 3) << "a refused change leaves the thread as it was";
    EXPECT_FALSE(down.error.empty());
  }
  EXPECT_EQ(nice_of_this_thread(), main_before) << "another thread's nice value is its own";
}

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

TEST(CommandOnce, TakesEachIdAndStampOnceAndForgetsTheOldest) {
  CommandOnce once(3);
  EXPECT_TRUE(once.first_time(7, 100));
  EXPECT_FALSE(once.first_time(7, 100));  // written again by a client that had not heard us
  EXPECT_TRUE(once.first_time(7, 101));   // the same id sent anew is a new command
  EXPECT_TRUE(once.first_time(8, 100));
  EXPECT_FALSE(once.first_time(8, 100));
  EXPECT_TRUE(once.first_time(9, 100));  // the fourth key pushes (7, 100) out
  EXPECT_TRUE(once.first_time(7, 100));
  EXPECT_FALSE(once.first_time(9, 100));
}

TEST(ResendUntilAnswered, WritesAgainEachPeriodUntilTheAnswerOrTheDeadline) {
  using Clock = std::chrono::steady_clock;
  using namespace std::chrono_literals;
  int writes = 0;
  // Answered at the third write: each unanswered wait lasts until its period ends.
  const auto t0 = Clock::now();
  EXPECT_TRUE(resend_until_answered([&] { ++writes; },
                                    [&](Clock::time_point until) {
                                      if (writes == 3) return true;
                                      std::this_thread::sleep_until(until);
                                      return false;
                                    },
                                    t0 + 5s, 20ms));
  EXPECT_EQ(writes, 3);
  EXPECT_GE(Clock::now() - t0, 40ms);

  // Never answered: written again after each period (at most deadline / period + 1 times, at
  // least twice unless one wait overshot by most of a second), then false.
  writes = 0;
  EXPECT_FALSE(resend_until_answered([&] { ++writes; },
                                     [&](Clock::time_point until) {
                                       std::this_thread::sleep_until(until);
                                       return false;
                                     },
                                     Clock::now() + 1s, 20ms));
  EXPECT_GE(writes, 2);
  EXPECT_LE(writes, 51);

  // A deadline already past still writes once.
  writes = 0;
  EXPECT_FALSE(resend_until_answered([&] { ++writes; }, [](Clock::time_point) { return false; },
                                     Clock::now() - 1s));
  EXPECT_EQ(writes, 1);
}

}  // namespace
}  // namespace concert
