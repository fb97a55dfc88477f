// Writes or checks idl/types.lock: the shape of every catalogue type. A type that changes
// without the lock being updated fails the test, with the difference and how to update.
//   idl_lock --check FILE | --write FILE
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "concert/dds/catalogue.hpp"
#include "concert/idl_schema/schema.hpp"

namespace {

std::map<std::string, std::string> current() {
  std::map<std::string, std::string> shapes;
  for (const auto& t : concert::dds::catalogue()) {
    shapes[std::string(t.type_name)] = concert::idl::Schema::builtin().shape(t.type_name);
  }
  return shapes;
}

std::string render(const std::map<std::string, std::string>& shapes) {
  std::ostringstream out;
  out << "# Shapes of the topic types (idl/*.idl). Generated: update with `make idl-lock`\n"
         "# after reviewing the change; a change here is a wire-contract change.\n";
  for (const auto& [name, shape] : shapes) out << "== " << name << "\n" << shape;
  return out.str();
}

std::map<std::string, std::string> parse(std::istream& in) {
  std::map<std::string, std::string> shapes;
  std::string line, name;
  while (std::getline(in, line)) {
    if (line.rfind("#", 0) == 0) continue;
    if (line.rfind("== ", 0) == 0) {
      name = line.substr(3);
      shapes[name];
    } else if (!name.empty()) {
      shapes[name] += line + "\n";
    }
  }
  return shapes;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 || (std::string(argv[1]) != "--check" && std::string(argv[1]) != "--write")) {
    std::cerr << "usage: idl_lock --check FILE | --write FILE\n";
    return 2;
  }
  const std::string file = argv[2];
  const auto now = current();
  if (std::string(argv[1]) == "--write") {
    std::ofstream(file) << render(now);
    std::cout << "idl_lock: wrote " << now.size() << " type shapes to " << file << "\n";
    return 0;
  }
  std::ifstream in(file);
  if (!in) {
    std::cerr << file << ": missing; create it with `make idl-lock`\n";
    return 1;
  }
  const auto locked = parse(in);
  int changed = 0;
  for (const auto& [name, shape] : now) {
    auto it = locked.find(name);
    if (it == locked.end()) {
      std::cerr << "type " << name << " is not in " << file << " (new type)\n";
      ++changed;
    } else if (it->second != shape) {
      std::cerr << "type " << name << " changed without updating " << file << ":\n--- locked\n"
                << it->second << "+++ now\n" << shape;
      ++changed;
    }
  }
  for (const auto& [name, shape] : locked) {
    if (!now.count(name)) {
      std::cerr << "type " << name << " is in " << file << " but no longer a topic type\n";
      ++changed;
    }
  }
  if (changed > 0) {
    std::cerr << changed << " type(s) differ from the lock. If the change is intended, run `make idl-lock`, "
                 "review the diff of idl/types.lock and commit it with the IDL change.\n";
    return 1;
  }
  std::cout << "idl_lock: " << now.size() << " types match " << file << "\n";
  return 0;
}
