#include "concert/ethercat/process_data.hpp"

#include <yaml-cpp/yaml.h>

#include <array>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>

namespace concert::ethercat {
namespace {

constexpr std::array<std::pair<EntryType, const char*>, 7> kTypes{{
    {EntryType::kInt8, "int8"},
    {EntryType::kInt16, "int16"},
    {EntryType::kInt32, "int32"},
    {EntryType::kUint8, "uint8"},
    {EntryType::kUint16, "uint16"},
    {EntryType::kUint32, "uint32"},
    {EntryType::kFloat32, "float32"},
}};

std::string at_line(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.line < 0 ? "" : " (line " + std::to_string(mark.line + 1) + ")";
}

std::vector<PdoEntry> parse_entries(const YAML::Node& list, const std::string& context) {
  std::vector<PdoEntry> entries;
  if (!list) return entries;
  if (!list.IsSequence()) throw ProcessDataError(context + ": expected a list" + at_line(list));
  std::size_t offset = 0;
  std::set<std::string> names;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node n = list[i];
    const std::string where = context + "[" + std::to_string(i) + "]";
    if (!n.IsMap() || !n["name"] || !n["type"]) {
      throw ProcessDataError(where + ": expected {name, type, index}" + at_line(n));
    }
    PdoEntry e;
    e.name = n["name"].as<std::string>();
    if (!names.insert(e.name).second) {
      throw ProcessDataError(where + ": entry '" + e.name + "' named twice" + at_line(n));
    }
    const std::string type = n["type"].as<std::string>();
    bool known = false;
    for (const auto& [value, text] : kTypes) {
      if (type == text) {
        e.type = value;
        known = true;
      }
    }
    if (!known) {
      throw ProcessDataError(where + ": type '" + type +
                             "' is not int8, int16, int32, uint8, uint16, uint32 or float32" +
                             at_line(n["type"]));
    }
    try {
      e.index = n["index"] ? n["index"].as<uint16_t>() : 0;
    } catch (const YAML::Exception&) {
      throw ProcessDataError(where + ": index is not a 16-bit number" + at_line(n["index"]));
    }
    e.offset = offset;
    offset += size_of(e.type);
    entries.push_back(std::move(e));
  }
  return entries;
}

}  // namespace

std::size_t size_of(EntryType type) {
  switch (type) {
    case EntryType::kInt8: case EntryType::kUint8: return 1;
    case EntryType::kInt16: case EntryType::kUint16: return 2;
    default: return 4;
  }
}

std::string to_string(EntryType type) {
  for (const auto& [value, text] : kTypes) {
    if (value == type) return text;
  }
  return "type " + std::to_string(static_cast<int>(type));
}

std::size_t BoardProcessData::output_bytes() const {
  return outputs.empty() ? 0 : outputs.back().offset + size_of(outputs.back().type);
}

std::size_t BoardProcessData::input_bytes() const {
  return inputs.empty() ? 0 : inputs.back().offset + size_of(inputs.back().type);
}

const PdoEntry* BoardProcessData::output(std::string_view n) const {
  for (const PdoEntry& e : outputs) if (e.name == n) return &e;
  return nullptr;
}

const PdoEntry* BoardProcessData::input(std::string_view n) const {
  for (const PdoEntry& e : inputs) if (e.name == n) return &e;
  return nullptr;
}

ProcessDataCatalog ProcessDataCatalog::load(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ProcessDataError(file.string() + ": cannot be read");
  std::stringstream text;
  text << in.rdbuf();
  return parse(text.str(), file.string());
}

ProcessDataCatalog ProcessDataCatalog::parse(std::string_view yaml, const std::string& source) {
  try {
    return parse_checked(yaml, source);
  } catch (const YAML::Exception& e) {
    // Whatever the checks below did not foresee still names the file.
    throw ProcessDataError(source + ": " + e.what());
  }
}

ProcessDataCatalog ProcessDataCatalog::parse_checked(std::string_view yaml, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(yaml));
  } catch (const YAML::Exception& e) {
    throw ProcessDataError(source + ": not YAML: " + e.what());
  }
  if (!root.IsMap()) throw ProcessDataError(source + ": expected a list 'boards:'");
  const YAML::Node boards = root["boards"];
  if (!boards || !boards.IsSequence()) throw ProcessDataError(source + ": expected a list 'boards:'");
  ProcessDataCatalog catalog;
  for (std::size_t i = 0; i < boards.size(); ++i) {
    const YAML::Node b = boards[i];
    const std::string where = source + ": boards[" + std::to_string(i) + "]";
    if (!b.IsMap() || !b["esc_type"]) throw ProcessDataError(where + ": missing 'esc_type'" + at_line(b));
    BoardProcessData board;
    try {
      board.esc_type = b["esc_type"].as<int32_t>();
    } catch (const YAML::Exception&) {
      throw ProcessDataError(where + ".esc_type: expected an integer" + at_line(b["esc_type"]));
    }
    if (catalog.find(board.esc_type)) {
      throw ProcessDataError(where + ": esc_type " + std::to_string(board.esc_type) + " listed twice" + at_line(b));
    }
    board.name = b["name"] ? b["name"].as<std::string>() : "esc_type " + std::to_string(board.esc_type);
    try {
      board.outputs = parse_entries(b["outputs"], where + ".outputs");
      board.inputs = parse_entries(b["inputs"], where + ".inputs");
    } catch (const YAML::Exception& e) {
      throw ProcessDataError(where + ": " + e.what());
    }
    // One PDO per direction: at most 255 entries (the SII's count byte), and the three buffers
    // of the outputs and the inputs within the ESC's 8 KiB of process RAM.
    for (const auto* list : {&board.outputs, &board.inputs}) {
      if (list->size() > 255) {
        throw ProcessDataError(where + ": " + std::to_string(list->size()) + " entries, more than 255" + at_line(b));
      }
    }
    if (3 * (board.output_bytes() + board.input_bytes()) > 0x1C00) {
      throw ProcessDataError(where + ": " + std::to_string(board.output_bytes()) + " bytes out and " +
                             std::to_string(board.input_bytes()) + " in do not fit an ESC's process RAM" + at_line(b));
    }
    catalog.boards_.push_back(std::move(board));
  }
  return catalog;
}

const BoardProcessData* ProcessDataCatalog::find(int32_t esc_type) const {
  for (const BoardProcessData& b : boards_) if (b.esc_type == esc_type) return &b;
  return nullptr;
}

void add_process_data(SiiInfo& sii, const BoardProcessData& board) {
  const auto out = static_cast<uint16_t>(board.output_bytes());
  const auto in_start = static_cast<uint16_t>(kOutputsStart + ((3 * out + 7) / 8) * 8);
  sii.sync_managers = {
      {.start = 0x1000, .length = 0, .control = 0x26, .enable = 0, .type = SiiSyncManager::kMailboxOut},
      {.start = 0x1080, .length = 0, .control = 0x22, .enable = 0, .type = SiiSyncManager::kMailboxIn},
      // Buffered, written by the master, PDI interrupt and watchdog trigger: 0x64 (outputs);
      // buffered, read by the master, PDI interrupt: 0x20 (inputs). Length 0: the PDOs say.
      {.start = kOutputsStart, .length = 0, .control = 0x64, .enable = static_cast<uint8_t>(out ? 1 : 0), .type = SiiSyncManager::kOutputs},
      {.start = in_start, .length = 0, .control = 0x20, .enable = static_cast<uint8_t>(board.input_bytes() ? 1 : 0), .type = SiiSyncManager::kInputs},
  };
  const auto pdo = [](uint16_t index, uint8_t sm, const std::vector<PdoEntry>& entries) {
    SiiPdo p;
    p.index = index;
    p.sync_manager = sm;
    for (const PdoEntry& e : entries) {
      // Each entry is a single-value CoE object (or padding, index 0): subindex 0.
      p.entries.push_back({.index = e.index, .subindex = 0,
                           .data_type = static_cast<uint8_t>(e.type),
                           .bits = static_cast<uint8_t>(8 * size_of(e.type))});
    }
    return p;
  };
  sii.rx_pdos.clear();
  sii.tx_pdos.clear();
  if (!board.outputs.empty()) sii.rx_pdos.push_back(pdo(0x1600, 2, board.outputs));
  if (!board.inputs.empty()) sii.tx_pdos.push_back(pdo(0x1A00, 3, board.inputs));
}

}  // namespace concert::ethercat
