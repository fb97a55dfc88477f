#pragma once
// The main of a Google Benchmark program (bench_* with BENCHMARK(...) registrations), on the
// project's command line instead of BENCHMARK_MAIN():
//
//   int main(int argc, char** argv) {
//     return concert::cli::benchmark_main("bench_x", "What it measures.", argc, argv);
//   }
//
// --help prints the usage and exits 0. Google Benchmark's own flags (--benchmark_filter=REGEX,
// --benchmark_repetitions=N, ...; always with '=') are passed on to it; any other argument, a
// flag without its value or a malformed value is refused with a message naming it, exit code 2.
// Header-only: only the programs that link benchmark::benchmark include it (concert_cli does not).
#include <benchmark/benchmark.h>

#include <iostream>
#include <string>
#include <vector>

#include "concert/cli/cli.hpp"

namespace concert::cli {

inline int benchmark_main(const std::string& name, const std::string& description, int argc,
                          char** argv) {
  Cli cli(name, description, std::cout, std::cerr);
  CLI::App& app = cli.app();
  app.allow_extras();
  app.footer(
      "Google Benchmark's flags are passed on, each as --flag=VALUE, e.g. "
      "--benchmark_filter=REGEX, --benchmark_repetitions=N, --benchmark_min_time=SECONDS, "
      "--benchmark_format=console|json|csv, --benchmark_out=FILE, "
      "--benchmark_out_format=console|json|csv, --benchmark_list_tests=true, "
      "--benchmark_report_aggregates_only=true.");
  cli.on_run(app, [&app, argv] {
    std::vector<std::string> args = app.remaining();
    for (const std::string& a : args) {
      if (a.rfind("--benchmark_", 0) != 0 && a.rfind("--v=", 0) != 0) {
        throw UsageError("unknown argument '" + a + "'");
      }
      // Google Benchmark 1.7 exits 0 after printing its usage for a bad format: refuse it here.
      for (const std::string flag : {"--benchmark_format=", "--benchmark_out_format="}) {
        if (a.rfind(flag, 0) == 0) {
          const std::string v = a.substr(flag.size());
          if (v != "console" && v != "json" && v != "csv") {
            throw UsageError(flag.substr(0, flag.size() - 1) + ": '" + v +
                             "' is not one of console, json, csv");
          }
        }
      }
    }
    std::vector<char*> bargv{argv[0]};
    for (std::string& a : args) bargv.push_back(a.data());
    bargv.push_back(nullptr);
    int bargc = static_cast<int>(bargv.size()) - 1;
    benchmark::Initialize(&bargc, bargv.data());
    // What Google Benchmark did not take (a flag without '=VALUE', a malformed number) it names
    // on stderr ("unrecognized command-line flag"): a wrong command line.
    if (benchmark::ReportUnrecognizedArguments(bargc, bargv.data())) return 2;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
  });
  return cli.run(argc, argv);
}

}  // namespace concert::cli
