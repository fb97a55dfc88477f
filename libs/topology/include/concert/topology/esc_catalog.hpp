#pragma once
// The ESC catalogue: what the network can know about module types, read from a module-database
// folder's esc_index.yaml (format of the public CONCERT file, plus optional extensions; see
// libs/topology/README.md).

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "concert/topology/esc_board.hpp"
#include "concert/topology/port_order.hpp"
#include "concert/topology/types.hpp"

namespace concert::topology {

/// Unreadable or inconsistent catalogue; what() names the file and the row or field.
class CatalogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Where one physical port of an ESC leads inside its module.
struct PortLead {
  int32_t port = 0;       ///< physical ESC port, 1..3
  int32_t connector = 0;  ///< output connector number (1-based); 0 when a secondary ESC hangs here
  std::optional<EscIdentity> secondary_esc;  ///< set: the module's next ESC hangs on this port
  bool operator==(const PortLead&) const = default;
};

/// One ESC identity the network can report, and what the database says about it.
struct EscType {
  EscIdentity identity;
  std::string key;    ///< module-database key (default: stem of `file`)
  std::string file;   ///< description file, relative to the database folder; may be empty
  ModuleKind kind = ModuleKind::kLink;
  std::optional<int32_t> outputs;  ///< explicit number of output connectors; empty = default
  std::vector<PortLead> ports;     ///< explicit port rows; empty = default mapping
  std::optional<EscBoard> board;   ///< `esc_ports: 2|4`; empty = default_board(kind)
  std::optional<int32_t> esc_type;  ///< ESC type register; empty = default_esc_type(kind, ...)
  std::string origin;              ///< "file: modules[i]", for messages
};

/// One ESC of a module layout.
struct EscPlacement {
  EscIdentity identity;
  EscBoard board = EscBoard::kTwoPort;  ///< ports the board has
  int32_t esc_type = 0;                 ///< what its ESC type register reads
  int32_t parent_esc = -1;   ///< index into ModuleLayout::escs; -1 for the upstream ESC
  int32_t parent_port = -1;  ///< port of the parent ESC it hangs on; -1 for the upstream ESC
};

/// Which ESC port an output connector is wired to.
struct ConnectorPlacement {
  int32_t connector = 0;  ///< 1-based connector number
  int32_t esc = 0;        ///< index into ModuleLayout::escs
  int32_t port = 0;       ///< physical port, 1..3
};

/// A module as the network sees it: its ESCs (upstream first, parents before children) and
/// where each output connector leads.
struct ModuleLayout {
  std::string key;
  ModuleKind kind = ModuleKind::kLink;
  std::vector<EscPlacement> escs;
  std::vector<ConnectorPlacement> connectors;  ///< sorted by connector number

  /// Number of output connectors.
  int32_t outputs() const { return static_cast<int32_t>(connectors.size()); }
  /// Placement of connector `number`, or nullptr.
  const ConnectorPlacement* connector(int32_t number) const;
  /// Connector wired to `port` of ESC `esc`, if any.
  std::optional<int32_t> connector_at(int32_t esc, int32_t port) const;
  /// Index of the ESC of this module hanging on `port` of ESC `esc`, if any.
  std::optional<int32_t> esc_at(int32_t esc, int32_t port) const;
};

/// Default number of output connectors of a single-ESC module without port rows:
/// joint, link, base link 1; end-effector, wheel 0; hub 3 (every port after 0). Without port
/// rows, connector k sits on the k-th downstream port of the board in frame order (esc_board.hpp):
/// port 1 on a two-port board; ports 3, 1, 2 on a four-port board (real order).
int32_t default_outputs(ModuleKind kind);

/// The catalogue of ESC identities of one or more module databases.
class EscCatalog {
 public:
  EscCatalog() = default;

  /// Reads `folder`/esc_index.yaml. Throws CatalogError.
  static EscCatalog load(const std::filesystem::path& folder);
  /// Reads one esc_index.yaml file. Throws CatalogError.
  static EscCatalog load_file(const std::filesystem::path& file);
  /// Parses esc_index.yaml text; `source` names it in messages. Throws CatalogError.
  static EscCatalog parse(std::string_view yaml_text, const std::string& source);

  /// Adds an entry, replacing one with the same identity. Throws CatalogError if the result
  /// has an inconsistent layout.
  void add(EscType type);
  /// Adds every entry of `other`; entries of `other` replace entries with the same identity.
  void merge(const EscCatalog& other);

  /// Entry for an identity, or nullptr.
  const EscType* find(const EscIdentity& identity) const;
  /// First entry (in file order) whose key is `key`, or nullptr.
  const EscType* find_key(std::string_view key) const;
  /// All entries, in the order they were added.
  const std::vector<EscType>& entries() const { return entries_; }

  /// Layout of the module whose upstream ESC has `upstream`. Throws CatalogError for an
  /// unknown identity or an inconsistent entry (duplicate connector, port out of range, ...).
  ModuleLayout layout(const EscIdentity& upstream, PortOrder order = PortOrder::kReal0312) const;

 private:
  void validate() const;

  std::vector<EscType> entries_;
  std::map<EscIdentity, std::size_t> by_identity_;
};

}  // namespace concert::topology
