#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace concert::bim {

/// Bad IFC input or a request the building cannot answer; the message names the file, the storey,
/// the element or the value and what is wrong.
class BimError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What a building element is, grouping IFC types (README "Element categories").
enum class Category {
  kWall,        ///< IfcWall, IfcWallStandardCase, IfcWallElementedCase, IfcCurtainWall
  kDoor,        ///< IfcDoor (passable: not in the occupancy map)
  kWindow,      ///< IfcWindow
  kColumn,      ///< IfcColumn
  kSlab,        ///< IfcSlab (floors, ceilings, roofs modelled as slabs: not in the map)
  kStair,       ///< IfcStair, IfcStairFlight, IfcRamp, IfcRampFlight
  kRailing,     ///< IfcRailing
  kCovering,    ///< IfcCovering (floor finishes, ceilings, claddings: not in the map)
  kFurnishing,  ///< IfcFurnishingElement, IfcFurniture
  kBeam,        ///< IfcBeam
  kMember,      ///< IfcMember, IfcPlate
  kRoof,        ///< IfcRoof
  kProxy,       ///< IfcBuildingElementProxy
};

/// "wall", "door", ... (the category names of the import format and geometry.json).
std::string to_string(Category category);
/// The category of a name from to_string(); throws BimError for another name.
Category category_from_string(const std::string& name);
/// True for the categories rasterised into the occupancy map and built into the simulated world:
/// everything except doors, slabs and coverings.
bool is_obstacle(Category category);

/// A triangle soup in the IFC world frame (Z up) [m].
struct Mesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;  ///< indices into vertices, 3 per triangle
};

/// A building element of the IFC file.
struct Element {
  std::string global_id;  ///< IFC GlobalId (22 characters)
  std::string ifc_type;   ///< e.g. "IfcWallStandardCase"
  Category category{Category::kWall};
  std::string name;              ///< IFC Name ("" when the file has none)
  std::string storey;            ///< GlobalId of its storey
  bool storey_by_height{false};  ///< in no storey in the file: assigned by its lowest point
  std::string host;  ///< doors and windows: GlobalId of the element whose opening they fill
  /// Origin and unit x axis of the element's mesh placement (world frame, Z up) [m]: for a wall,
  /// the start of its axis and the axis direction; unset when the element has no mesh.
  std::optional<Eigen::Vector3d> placement_origin;
  std::optional<Eigen::Vector3d> placement_x;
  Mesh mesh;  ///< openings already cut (web-ifc); empty when the engine made no geometry
  Eigen::AlignedBox3d bounds;  ///< of the mesh [m]; empty() when there is no mesh
};

/// An IfcBuildingStorey.
struct Storey {
  std::string name;  ///< IFC Name (the GlobalId when the file has none)
  std::string global_id;
  double elevation{0.0};  ///< world z of the storey's placement (its floor level) [m]
};

/// A building read from an IFC file: storeys from the lowest up, elements in file-type order.
struct BimModel {
  std::string source;         ///< the IFC file
  std::string schema;         ///< "IFC2X3", "IFC4", ...
  double length_unit_m{1.0};  ///< the file's length unit [m] (everything here is in metres)
  std::vector<Storey> storeys;
  std::vector<Element> elements;

  /// The storey with this name or GlobalId. Throws BimError
  /// "storey 'X' not found in FILE; storeys: A, B".
  [[nodiscard]] const Storey& storey(const std::string& name_or_id) const;
  /// The element with this GlobalId. Throws BimError "no element with GlobalId 'X' in FILE".
  [[nodiscard]] const Element& element(const std::string& global_id) const;
  /// The elements assigned to `storey` (by containment, else by height).
  [[nodiscard]] std::vector<const Element*> elements_of(const Storey& storey) const;
  /// Height of `storey` up to the next storey's elevation; `fallback` for the top storey [m].
  [[nodiscard]] double storey_height(const Storey& storey, double fallback = 3.0) const;
};

/// How load_ifc runs the import step (tools/ifc_import/ifc_import.mjs on Node.js).
struct ImportOptions {
  std::string script;        ///< "" = default_import_script()
  std::string node{"node"};  ///< the Node.js executable (looked up in PATH)
  std::string keep_dir;      ///< "" = a temporary folder, removed; else the import output is kept
                             ///< there as model.json + model.bin (read_import reads it back)
};

/// The import step's script: $CONCERT_IFC_IMPORT when set, else the path compiled in
/// (the source tree's tools/ifc_import/ifc_import.mjs).
std::string default_import_script();

/// Reads an IFC2x3/IFC4 file: runs the import step as a child process (its stderr becomes the
/// error message) and reads its output. Throws BimError naming the file: missing, not IFC,
/// truncated, an engine failure, or a building without walls.
BimModel load_ifc(const std::string& ifc_path, const ImportOptions& options = {});

/// Reads the import step's output (`json_path` and the binary file it names beside it).
/// Throws BimError naming the file and the field on bad content.
BimModel read_import(const std::string& json_path);

/// A file-name-safe form of a storey name: lower case ASCII letters, digits and '-', e.g.
/// "Level 1" -> "level-1", "T/FDN" -> "t-fdn" ("storey" when nothing is left).
std::string slug(const std::string& name);

}  // namespace concert::bim
