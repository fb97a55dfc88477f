// Syntax and placement checks of the deployment files: deploy/compose.yaml parsed as YAML with
// its merge keys resolved and checked against the compose specification's keys and the three-PC
// placement; deploy/Dockerfile builds and stages every service compose runs. The compose CLIs
// installed here (Debian's docker-compose 1.29, Docker Compose v2 where present) must accept
// the file (`config`, no engine needed); a CLI that is not installed is reported skipped. The
// deployment itself runs in tests/deploy/compose_three_pcs.sh.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace concert::system_test {
namespace {

using ::testing::HasSubstr;

namespace fs = std::filesystem;
const fs::path kDeploy = fs::path(CONCERT_SOURCE_DIR) / "deploy";

/// yaml-cpp keeps `<<: *anchor` as an ordinary key: apply YAML merge keys (local keys win).
YAML::Node resolve_merges(const YAML::Node& node) {
  if (node.IsSequence()) {
    YAML::Node out(YAML::NodeType::Sequence);
    for (const auto& item : node) out.push_back(resolve_merges(item));
    return out;
  }
  if (!node.IsMap()) return node;
  YAML::Node out(YAML::NodeType::Map);
  for (const auto& entry : node) {
    if (entry.first.Scalar() != "<<") out[entry.first.Scalar()] = resolve_merges(entry.second);
  }
  if (const auto merge = node["<<"]) {
    std::vector<YAML::Node> sources;
    if (merge.IsSequence()) {
      for (const auto& m : merge) sources.push_back(m);
    } else {
      sources.push_back(merge);
    }
    for (const auto& source : sources) {
      const auto resolved = resolve_merges(source);
      for (const auto& entry : resolved) {
        if (!out[entry.first.Scalar()]) out[entry.first.Scalar()] = entry.second;
      }
    }
  }
  return out;
}

/// "${VAR:-default}" -> "default"; other text unchanged.
std::string with_defaults(const std::string& text) {
  return std::regex_replace(text, std::regex(R"(\$\{[A-Z_]+:-([^}]*)\})"), "$1");
}

const std::map<std::string, std::string> kPlacement = {
    {"robot", "rt"},    {"safety", "rt"},    {"discovery", "rt"},
    {"modelgen", "rt"}, {"nav", "nav"},      {"planner", "manip"},
    {"gui", "nav"},     {"drill", "manip"}, {"collab", "manip"}, {"surface_finish", "manip"}};
const std::map<std::string, std::string> kHostOf = {
    {"rt", "rt-pc"}, {"nav", "nav-pc"}, {"manip", "manip-pc"}};

// Service keys of the compose specification that this file may use.
const std::set<std::string> kServiceKeys = {
    "image",      "build",       "command",      "entrypoint",  "environment",
    "env_file",   "volumes",     "network_mode", "networks",    "ipc",
    "pid",        "restart",     "init",         "stop_signal", "stop_grace_period",
    "profiles",   "deploy",      "cap_add",      "cap_drop",    "ulimits",
    "hostname",   "depends_on",  "healthcheck",  "labels",      "devices",
    "privileged", "user",        "working_dir",  "shm_size",    "sysctls",
    "logging",    "extra_hosts", "security_opt", "cpuset"};

YAML::Node load_compose() {
  return resolve_merges(YAML::LoadFile((kDeploy / "compose.yaml").string()));
}

TEST(DeployCompose, ParsesWithOnlyComposeKeys) {
  YAML::Node compose;
  ASSERT_NO_THROW(compose = load_compose());
  ASSERT_TRUE(compose.IsMap());
  for (const auto& entry : compose) {
    const auto key = entry.first.Scalar();
    // No `name:`: Debian 12's docker-compose 1.29 refuses it (the project comes from -p).
    EXPECT_TRUE(key.rfind("x-", 0) == 0 || key == "services" || key == "volumes" || key == "networks" ||
                key == "configs" || key == "secrets")
        << "top-level key '" << key << "' (not one docker-compose 1.29 accepts)";
  }
  ASSERT_TRUE(compose["services"].IsMap());
  for (const auto& service : compose["services"]) {
    const auto name = service.first.Scalar();
    for (const auto& key : service.second) {
      EXPECT_TRUE(kServiceKeys.count(key.first.Scalar()))
          << name << ": unknown key '" << key.first.Scalar() << "'";
    }
  }
}

TEST(DeployCompose, EveryServiceOnItsPcWithHostNetworkingAndDds) {
  const auto compose = load_compose();
  std::set<std::string> seen;
  for (const auto& entry : compose["services"]) {
    const auto name = entry.first.Scalar();
    const auto& s = entry.second;
    seen.insert(name);
    ASSERT_TRUE(kPlacement.count(name))
        << "service '" << name << "' is not one of the stack's services";
    const auto pc = kPlacement.at(name);
    EXPECT_FALSE(s["image"].Scalar().empty()) << name;
    EXPECT_EQ(s["network_mode"].Scalar(), "host") << name;
    // DDS runs over UDP (no shared memory: libs/dds participant.cpp); a private IPC namespace.
    EXPECT_FALSE(s["ipc"]) << name << ": no shared IPC namespace is needed";
    EXPECT_FALSE(s["hostname"]) << name
                                << ": docker refuses hostname together with network_mode host";
    ASSERT_TRUE(s["profiles"].IsSequence()) << name;
    EXPECT_EQ(s["profiles"].size(), 1u) << name;
    EXPECT_EQ(s["profiles"][0].Scalar(), pc) << name;
    ASSERT_TRUE(s["deploy"]["placement"]["constraints"].IsSequence()) << name;
    EXPECT_EQ(s["deploy"]["placement"]["constraints"][0].Scalar(),
              "node.labels.concert.pc == " + pc)
        << name;
    const auto env = s["environment"];
    ASSERT_TRUE(env.IsMap()) << name;
    EXPECT_TRUE(env["CONCERT_DOMAIN_ID"]) << name;
    EXPECT_EQ(env["CONCERT_HOST"].Scalar(), kHostOf.at(pc)) << name;
    EXPECT_EQ(env["CONCERT_DDS_PROFILES"].Scalar(), "/etc/concert/fastdds_profiles.xml") << name;
    ASSERT_TRUE(s["command"].IsSequence()) << name;
    EXPECT_EQ(s["command"][0].Scalar(), "concert_" + name) << name;
    bool profile_mounted = false;
    for (const auto& v : s["volumes"]) {
      const auto spec = with_defaults(v.Scalar());
      const auto source = spec.substr(0, spec.find(':'));
      if (source.rfind("./", 0) == 0) {
        EXPECT_TRUE(fs::exists(kDeploy / source))
            << name << ": volume source " << source << " is missing";
      } else {
        EXPECT_TRUE(compose["volumes"][source])
            << name << ": named volume '" << source << "' is not declared";
      }
      profile_mounted |= spec.find(":/etc/concert/fastdds_profiles.xml") != std::string::npos;
    }
    EXPECT_TRUE(profile_mounted) << name;
  }
  for (const auto& [name, pc] : kPlacement)
    EXPECT_TRUE(seen.count(name)) << name << " (" << pc << ") is missing";
}

/// Runs `command`; its exit code (-1 when it could not run).
int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// `cli config -q` for every profile; skipped (its own ctest entries: system_deploy_compose_cli_
/// test for Debian's docker-compose, system_deploy_compose_v2_test for Docker Compose v2) when the
/// CLI is not installed.
void compose_cli_accepts_it(const std::string& cli) {
  if (run(cli + " version > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "`" << cli << "` is not installed here: compose.yaml was not checked with it";
  }
  for (const char* profile : {"rt", "nav", "manip"}) {
    const auto cmd = cli + " -p concert -f '" + (kDeploy / "compose.yaml").string() + "' --profile " +
                     profile + " config -q 2>&1";
    EXPECT_EQ(run(cmd), 0) << cmd;
  }
}

TEST(DeployCompose, DockerComposeV1AcceptsIt) { compose_cli_accepts_it("docker-compose"); }
TEST(DeployCompose, DockerComposeV2AcceptsIt) { compose_cli_accepts_it("docker compose"); }

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(DeployDockerfile, BuildsAndStagesEveryServiceComposeRuns) {
  const auto dockerfile = read_text(kDeploy / "Dockerfile");
  ASSERT_FALSE(dockerfile.empty());
  EXPECT_THAT(dockerfile, HasSubstr("ARG DEBIAN_IMAGE=debian:12"));
  EXPECT_THAT(dockerfile, HasSubstr("RUN /opt/concert/src/deploy/install-deps.sh"));
  // The runtime stage: the same steps as the image `make image` builds.
  EXPECT_THAT(dockerfile, HasSubstr("/opt/concert/src/deploy/image/stage.sh /opt/concert/build /opt/concert/stage"));
  EXPECT_THAT(dockerfile, HasSubstr("RUN /opt/concert/deploy/install-deps.sh --runtime"));
  const auto containerfile = read_text(kDeploy / "image" / "Containerfile");
  EXPECT_THAT(containerfile, HasSubstr("RUN /opt/concert/deploy/install-deps.sh --runtime"));
  const std::regex copy(R"(^COPY (?!--from)(\S+) )", std::regex::multiline);
  for (auto it = std::sregex_iterator(dockerfile.begin(), dockerfile.end(), copy);
       it != std::sregex_iterator(); ++it) {
    const auto source = (*it)[1].str();
    EXPECT_TRUE(fs::exists(fs::path(CONCERT_SOURCE_DIR) / source)) << "COPY source missing: " << source;
  }
  // Every executable compose runs is built by the Dockerfile and staged into the image.
  std::smatch staged;
  const auto stage = read_text(kDeploy / "image" / "stage.sh");
  ASSERT_TRUE(std::regex_search(stage, staged, std::regex(R"(\nservices=\(([^)]*)\))")))
      << "deploy/image/stage.sh has no services=(...) list";
  const std::string staged_list = " " + staged[1].str() + " ";
  const auto compose = load_compose();
  for (const auto& entry : compose["services"]) {
    const auto binary = entry.second["command"][0].Scalar();
    EXPECT_THAT(dockerfile, HasSubstr(" " + binary)) << binary << " is not built by the Dockerfile";
    const auto service = binary.substr(std::string("concert_").size());
    EXPECT_THAT(staged_list, HasSubstr(" " + service + " ")) << binary << " is not staged by deploy/image/stage.sh";
  }
}

}  // namespace
}  // namespace concert::system_test
