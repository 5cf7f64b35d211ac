#include "sim/object_library.h"

#include <cmath>
#include <iomanip>
#include <mutex>
#include <optional>
#include <sstream>

#include "common/config_error.h"
#include "common/data_dir.h"
#include "common/yaml_map.h"
#include "sim/object_shapes.h"

namespace graspbed::sim {

ObjectLibrary ObjectLibrary::LoadFile(const std::string& path) {
  const common::YamlMap root = common::YamlMap::LoadFile(path);
  ObjectLibrary library;
  library.path_ = path;
  const std::vector<common::YamlMap> entries = root.GetMapList("objects");
  root.RejectUnknownKeys();
  if (entries.empty()) root.FailHere("no objects: expected a list under `objects`");
  for (const common::YamlMap& entry : entries) {
    LibraryObject object;
    object.name = entry.RequireString("name");
    if (library.Find(object.name) != nullptr) entry.Fail("name", "a second object of this name");
    object.description = entry.GetString("description", "");
    object.source = entry.GetString("source", "");
    object.notes = entry.GetString("notes", "");
    if (object.source.empty()) entry.FailHere("no `source`: name the published figures, or say they are chosen");
    object.object = LoadLibraryObjectConfig(entry, {"description", "source", "notes"});
    library.objects_.push_back(std::move(object));
  }
  return library;
}

const LibraryObject* ObjectLibrary::Find(const std::string& name) const {
  for (const LibraryObject& object : objects_) {
    if (object.name == name) return &object;
  }
  return nullptr;
}

std::string ObjectLibrary::NameList() const {
  std::string names;
  for (const LibraryObject& object : objects_) names += (names.empty() ? "" : ", ") + object.name;
  return names;
}

std::vector<ObjectSummary> SummarizeObjects(const ObjectLibrary& library) {
  std::vector<ObjectSummary> rows;
  for (const LibraryObject& entry : library.objects()) {
    const ObjectConfig& o = entry.object;
    const std::vector<ObjectPart> parts = ObjectParts(o);
    const MassProperties props = ComputeMassProperties(parts);
    ObjectSummary row;
    row.name = entry.name;
    row.shape = ToString(o.shape);
    row.description = entry.description;
    row.size_m = o.size_m;
    row.mass_kg = props.mass_kg;
    const Eigen::Vector3d principal = props.PrincipalMomentsKgM2();
    for (int k = 0; k < 3; ++k) {
      row.centre_of_mass_m[k] = props.centre_of_mass_m[k];
      row.principal_inertia_kg_m2[k] = principal[k];
    }
    row.friction = o.friction;
    row.stiffness_n_m = o.stiffness_n_m.value_or(StiffnessOfSolref(o));
    row.solref_timeconst_s = o.solref_timeconst_s;
    row.crush_limit_n = o.crush_limit_n;
    row.fill_fraction = o.fill_fraction;
    row.part_count = static_cast<int>(parts.size());
    row.default_grasp = DefaultGrasp(o, HandConfig{});
    row.source = entry.source;
    row.notes = entry.notes;
    rows.push_back(std::move(row));
  }
  return rows;
}

namespace {

std::string Fixed(double value, int digits) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << (std::abs(value) < 0.5 * std::pow(10.0, -digits) ? 0.0 : value);
  return out.str();
}

}  // namespace

std::string SizeTextMm(const ObjectSummary& row) {
  const auto mm = [&row](int k) { return Fixed(row.size_m[k] * 1e3, 0); };
  if (row.shape == "cylinder" || row.shape == "egg") return "dia " + mm(0) + " x " + mm(2);
  if (row.shape == "sphere") return "dia " + mm(0);
  if (row.shape == "mug") return "dia " + mm(0) + " x " + mm(2) + ", " + mm(1) + " deep with handle";
  if (row.shape == "bottle") return "dia " + mm(0) + " x " + mm(2) + ", neck " + mm(1);
  if (row.shape == "cup") return "rim " + mm(0) + ", base " + mm(1) + " x " + mm(2);
  if (row.shape == "wine_glass") return "bowl " + mm(0) + ", foot " + mm(1) + " x " + mm(2);
  if (row.shape == "banana") return "chord " + mm(0) + ", " + mm(1) + " thick, bow " + mm(2);
  return mm(0) + " x " + mm(1) + " x " + mm(2);  // a box, a mesh's bounding box
}

namespace {

std::string CentreMm(const ObjectSummary& row) {
  return Fixed(row.centre_of_mass_m[0] * 1e3, 1) + ", " + Fixed(row.centre_of_mass_m[1] * 1e3, 1) + ", " +
         Fixed(row.centre_of_mass_m[2] * 1e3, 1);
}

std::string Stiffness(double n_m) {
  std::ostringstream out;
  out << std::setprecision(2) << n_m;
  return out.str();
}

}  // namespace

std::string ObjectTableText(const std::vector<ObjectSummary>& rows) {
  std::ostringstream out;
  const auto line = [&out](const std::string& name, const std::string& shape, const std::string& size,
                           const std::string& mass, const std::string& com, const std::string& friction,
                           const std::string& stiffness, const std::string& crush, const std::string& grasp) {
    out << std::left << std::setw(12) << name << std::setw(11) << shape << std::setw(35) << size << std::right
        << std::setw(8) << mass << "  " << std::left << std::setw(20) << com << std::right << std::setw(10)
        << friction << std::setw(13) << stiffness << std::setw(11) << crush << "  " << grasp << '\n';
  };
  line("name", "shape", "size [mm]", "mass [g]", "centre of mass [mm]", "friction", "stiff [N/m]",
       "crush [N]", "grasp");
  for (const ObjectSummary& row : rows) {
    line(row.name, row.shape, SizeTextMm(row), Fixed(row.mass_kg * 1e3, 1), CentreMm(row),
         Fixed(row.friction, 2), Stiffness(row.stiffness_n_m),
         row.crush_limit_n > 0.0 ? Fixed(row.crush_limit_n, 1) : "-", ToString(row.default_grasp));
  }
  out << "\nsize: object.size_m as the shape reads it, dia = diameter, heights last "
         "(docs/scenarios.md, \"Object library\"); centre of mass from the centre of the bounding box "
         "(a mug: its body's axis); grasp: the one a scenario naming the object gets unless it sets "
         "hand.grasp\n";
  for (const ObjectSummary& row : rows) out << row.name << ": " << row.source << '\n';
  return out.str();
}

std::string ObjectTableMarkdown(const std::vector<ObjectSummary>& rows) {
  std::ostringstream out;
  out << "| object | shape | size [mm] | mass [g] | centre of mass [mm] | friction | stiffness [N/m] | "
         "crush [N] | grasp | source |\n";
  out << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const ObjectSummary& row : rows) {
    out << "| `" << row.name << "` | " << row.shape << " | " << SizeTextMm(row) << " | "
        << Fixed(row.mass_kg * 1e3, 1) << " | " << CentreMm(row) << " | " << Fixed(row.friction, 2) << " | "
        << Stiffness(row.stiffness_n_m) << " | "
        << (row.crush_limit_n > 0.0 ? Fixed(row.crush_limit_n, 1) : "-") << " | "
        << ToString(row.default_grasp) << " | " << row.source << " |\n";
  }
  return out.str();
}

const ObjectLibrary& ShippedObjectLibrary() {
  static std::once_flag once;
  static std::optional<ObjectLibrary> library;
  std::call_once(once, [] { library = ObjectLibrary::LoadFile(common::DataPath(kObjectLibraryPath)); });
  return *library;
}

}  // namespace graspbed::sim
