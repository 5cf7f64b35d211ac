#pragma once
/// The object library: named everyday objects a scenario picks with one key (`object: {name: mug}`),
/// every other object key beside `name` overriding the entry's value (`object: {name: can, mass_kg:
/// 0.2}`). The entries live in a data file shipped with graspbed, `models/objects.yaml` under
/// common::DataDir(); each gives its shape, size, mass, friction against the pad, stiffness, crush
/// force and the published figures they come from. Docs: docs/scenarios.md, "Object library".

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "sim/scene_config.h"

namespace graspbed::sim {

/// The library file below common::DataDir().
inline constexpr const char* kObjectLibraryPath = "models/objects.yaml";

/// One named object.
struct LibraryObject {
  std::string name;         ///< the key scenarios use (`object: {name: ...}`)
  std::string description;  ///< one line: what it is
  /// Where its dimensions and mass come from ("YCB 005 tomato soup can, Calli et al. 2015, Table 1: ...")
  /// or "no YCB counterpart: chosen figures ...".
  std::string source;
  /// Why its friction, stiffness and crush force are what they are.
  std::string notes;
  ObjectConfig object;  ///< the resolved object (stiffness turned into solref/solimp, name set)
};

/// The objects of one library file, in file order.
class ObjectLibrary {
 public:
  /// Reads `path`: a map with key `objects`, a list of maps each holding `name`, `description`,
  /// `source`, `notes` and the keys of a scenario's `object:` section.
  /// @throws common::ConfigError naming the file, line, key and value (an unknown key, a value out of
  ///   range, a duplicate name, an object the hand cannot hold).
  static ObjectLibrary LoadFile(const std::string& path);

  const std::vector<LibraryObject>& objects() const { return objects_; }
  /// The entry called `name`, or nullptr.
  const LibraryObject* Find(const std::string& name) const;
  /// The names, comma separated, in file order (for "unknown name" errors).
  std::string NameList() const;
  /// The file it was read from.
  const std::string& path() const { return path_; }

 private:
  std::vector<LibraryObject> objects_;
  std::string path_;
};

/// One library object's figures as `graspbed objects` lists them; SI units, object frame
/// (sim/object_shapes.h).
struct ObjectSummary {
  std::string name;
  std::string shape;
  std::string description;
  std::array<double, 3> size_m{};            ///< object.size_m as the shape reads it [m]
  double mass_kg = 0.0;                      ///< total [kg]
  std::array<double, 3> centre_of_mass_m{};  ///< from the bounding-box centre (a mug's axis) [m]
  std::array<double, 3> principal_inertia_kg_m2{};  ///< about the centre of mass, ascending [kg m^2]
  double friction = 0.0;                     ///< against the pad [-]
  double stiffness_n_m = 0.0;                ///< against a rigid surface: stated, or from solref [N/m]
  double solref_timeconst_s = 0.0;           ///< [s]
  double crush_limit_n = 0.0;                ///< 0 = does not break [N]
  std::optional<double> fill_fraction;       ///< bottles
  int part_count = 0;                        ///< MuJoCo geoms
  /// The grasp a scenario gets when it names the object and no grasp (DefaultGrasp, prosthetic hand).
  GraspType default_grasp = GraspType::kPinch;
  std::string source;
  std::string notes;
};

/// The summaries of every object of `library`, in file order.
std::vector<ObjectSummary> SummarizeObjects(const ObjectLibrary& library);
/// object.size_m as a person reads it for the shape, in mm: a box "w x d x h", a cylinder or an egg
/// "dia 66 x 101" (diameter x height), a sphere "dia 65", a mug "dia 80 x 82, 117 deep with handle", a
/// bottle "dia 65 x 220, neck 28", a cup "rim 70, base 46 x 80", a wine glass "bowl 80, foot 70 x
/// 190", a banana "chord 160, 36 thick, bow 30", a mesh its bounding box.
std::string SizeTextMm(const ObjectSummary& row);
/// An aligned plain-text table of `rows` (sizes and centre of mass in mm, mass in g), then one
/// "name: source" line each.
std::string ObjectTableText(const std::vector<ObjectSummary>& rows);
/// The same as a Markdown table (docs/scenarios.md, "Object library").
std::string ObjectTableMarkdown(const std::vector<ObjectSummary>& rows);

/// The shipped library (common::DataPath(kObjectLibraryPath)), read once per process.
/// @throws common::ConfigError as LoadFile, std::runtime_error when there is no data directory.
const ObjectLibrary& ShippedObjectLibrary();

}  // namespace graspbed::sim
