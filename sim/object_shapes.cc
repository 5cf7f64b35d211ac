#include "sim/object_shapes.h"

#include "sim/simulation.h"

#include <mujoco/mujoco.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace graspbed::sim {
namespace {

constexpr double kPi = std::numbers::pi;

// Mug: ceramic wall and handle [m]; the handle's share of the mass follows their volumes.
constexpr double kMugWallM = 0.005;
constexpr double kMugHandleRadiusM = 0.005;
// Bottle: body up to 70 % of the height, shoulder to 85 %, then the neck; the liquid fills the body
// inside a 1 mm wall.
constexpr double kBottleBodyShare = 0.70;
constexpr double kBottleShoulderShare = 0.85;
constexpr double kBottleWallM = 0.001;
// Wine glass: foot disc, stem, bowl from 45 % of the height; mass shares of glass (stated, typical
// of a 150-200 g stemmed glass).
constexpr double kGlassFootThicknessM = 0.004;
constexpr double kGlassStemRadiusM = 0.0035;
constexpr double kGlassBowlStartShare = 0.45;
constexpr double kGlassBowlShare = 0.55;
constexpr double kGlassStemShare = 0.15;
// Egg: equator at 45 % of the length from the blunt end.
constexpr double kEggEquatorShare = 0.45;
constexpr int kEggRingsPerHalf = 8;
// Banana: capsules along the arc.
constexpr int kBananaSegments = 5;

ObjectPart Primitive(ObjectPart::Type type, std::string role, std::array<double, 3> size, Eigen::Vector3d at,
                     double mass_kg, Eigen::Vector3d axis = Eigen::Vector3d::UnitZ()) {
  ObjectPart part;
  part.type = type;
  part.role = std::move(role);
  part.size_m = size;
  part.position_m = at;
  part.axis = axis.normalized();
  part.mass_kg = mass_kg;
  return part;
}

// A capsule between two points of radius r.
ObjectPart Capsule(std::string role, const Eigen::Vector3d& from, const Eigen::Vector3d& to, double radius,
                   double mass_kg) {
  return Primitive(ObjectPart::Type::kCapsule, std::move(role), {radius, 0.5 * (to - from).norm(), 0.0},
                   0.5 * (from + to), mass_kg, to - from);
}

// A convex solid of revolution about z: rings of kRevolutionSegments vertices at each profile point
// (one vertex where the radius is 0). The profile must be convex (radius concave in z).
ObjectPart Revolution(std::string role, std::vector<std::array<double, 2>> profile, double mass_kg) {
  ObjectPart part;
  part.type = ObjectPart::Type::kMesh;
  part.role = std::move(role);
  part.mass_kg = mass_kg;
  for (const auto& [radius, z] : profile) {
    if (radius < 1e-9) {
      part.vertices_m.emplace_back(0.0, 0.0, z);
      continue;
    }
    for (int i = 0; i < kRevolutionSegments; ++i) {
      const double angle = 2.0 * kPi * i / kRevolutionSegments;
      part.vertices_m.emplace_back(radius * std::cos(angle), radius * std::sin(angle), z);
    }
  }
  part.profile_m = std::move(profile);
  return part;
}

double Square(double x) { return x * x; }

// Mass properties of one part about its own centre of mass, object axes: mass-normalised inertia
// (per kg) and the centre of mass.
struct UnitInertia {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d per_kg = Eigen::Matrix3d::Zero();
};

// Axisymmetric inertia per kg (axial, transverse) turned so its axis lies along `axis`.
Eigen::Matrix3d AlongAxis(double axial, double transverse, const Eigen::Vector3d& axis) {
  const Eigen::Vector3d a = axis.normalized();
  return transverse * Eigen::Matrix3d::Identity() + (axial - transverse) * a * a.transpose();
}

// The polygonal frustums between consecutive profile points, sliced: exact for regular
// kRevolutionSegments-gons whose circumradius varies linearly along each segment.
UnitInertia RevolutionInertia(const std::vector<std::array<double, 2>>& profile) {
  const int n = kRevolutionSegments;
  const double area_factor = 0.5 * n * std::sin(2.0 * kPi / n);                  // A = f r^2
  const double polar_factor = (1.0 + 2.0 * Square(std::cos(kPi / n))) / 6.0;     // J = A r^2 g
  double volume = 0.0, first_z = 0.0;
  constexpr int kSlices = 2000;
  struct Slice {
    double z, area, polar, dz;
  };
  std::vector<Slice> slices;
  for (size_t k = 0; k + 1 < profile.size(); ++k) {
    const auto [r0, z0] = profile[k];
    const auto [r1, z1] = profile[k + 1];
    const double dz = (z1 - z0) / kSlices;
    for (int s = 0; s < kSlices; ++s) {
      const double t = (s + 0.5) / kSlices;
      const double r = r0 + t * (r1 - r0);
      const double area = area_factor * r * r;
      slices.push_back({z0 + t * (z1 - z0), area, area * r * r * polar_factor, dz});
      volume += area * dz;
      first_z += area * dz * (z0 + t * (z1 - z0));
    }
  }
  UnitInertia u;
  u.centre.z() = first_z / volume;
  double polar = 0.0, transverse = 0.0;
  for (const Slice& s : slices) {
    polar += s.polar * s.dz;
    transverse += (0.5 * s.polar + s.area * Square(s.z - u.centre.z())) * s.dz;
  }
  u.per_kg = Eigen::Vector3d(transverse, transverse, polar).asDiagonal();
  u.per_kg /= volume;
  return u;
}

// A convex mesh's inertia from its hull: tetrahedra from its centroid to each hull face. The hull
// comes from MuJoCo (below), so only the vertices are needed here: fan the hull's faces.
UnitInertia HullInertia(const std::vector<Eigen::Vector3d>& vertices);

UnitInertia PartInertia(const ObjectPart& part) {
  UnitInertia u;
  u.centre = part.position_m;
  const auto& s = part.size_m;
  switch (part.type) {
    case ObjectPart::Type::kBox:
      u.per_kg = Eigen::Vector3d(Square(2 * s[1]) + Square(2 * s[2]), Square(2 * s[0]) + Square(2 * s[2]),
                                 Square(2 * s[0]) + Square(2 * s[1]))
                     .asDiagonal();
      u.per_kg /= 12.0;
      break;
    case ObjectPart::Type::kCylinder:
      u.per_kg = AlongAxis(0.5 * s[0] * s[0], (3 * s[0] * s[0] + Square(2 * s[1])) / 12.0, part.axis);
      break;
    case ObjectPart::Type::kSphere:
      u.per_kg = 0.4 * s[0] * s[0] * Eigen::Matrix3d::Identity();
      break;
    case ObjectPart::Type::kCapsule: {
      // Cylinder of length h plus two hemispheres (each's centre of mass 3r/8 from its flat face).
      const double r = s[0], h = 2 * s[1];
      const double cylinder = kPi * r * r * h, sphere = 4.0 / 3.0 * kPi * r * r * r;
      const double total = cylinder + sphere;
      const double axial = (cylinder * 0.5 * r * r + sphere * 0.4 * r * r) / total;
      const double transverse =
          (cylinder * (3 * r * r + h * h) / 12.0 + sphere * (83.0 / 320.0 * r * r + Square(0.5 * h + 3.0 * r / 8.0))) /
          total;
      u.per_kg = AlongAxis(axial, transverse, part.axis);
      break;
    }
    case ObjectPart::Type::kMesh:
      if (!part.profile_m.empty()) {
        u = RevolutionInertia(part.profile_m);
      } else {
        u = HullInertia(part.vertices_m);
      }
      break;
  }
  return u;
}

// Mass properties of a single body holding the given geoms, as MuJoCo compiles them.
struct CompiledBody {
  double mass = 0.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
};

// Compiles `<body><geom type="mesh" density="1"/></body>` for the vertices' hull: its mass is the
// hull's volume, its inertia the hull's (per unit density).
CompiledBody CompileHull(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 4) throw std::invalid_argument("a mesh needs at least 4 vertices");
  std::ostringstream xml;
  xml << std::setprecision(17);
  xml << "<mujoco><compiler inertiafromgeom=\"true\"/><asset><mesh name=\"m\" vertex=\"";
  for (const Eigen::Vector3d& p : points) xml << p.x() << " " << p.y() << " " << p.z() << " ";
  xml << "\"/></asset><worldbody><body><freejoint/><geom type=\"mesh\" mesh=\"m\" density=\"1\"/></body>"
         "</worldbody></mujoco>";
  mjModel* model = nullptr;
  try {
    model = CompileMjcf(xml.str());
  } catch (const std::runtime_error& error) {
    throw std::invalid_argument(std::string("MuJoCo refused the mesh: ") + error.what());
  }
  CompiledBody body;
  body.mass = model->body_mass[1];
  body.centre = Eigen::Vector3d(model->body_ipos[3], model->body_ipos[4], model->body_ipos[5]);
  const Eigen::Quaterniond q(model->body_iquat[4], model->body_iquat[5], model->body_iquat[6],
                             model->body_iquat[7]);
  const Eigen::Matrix3d rot = q.toRotationMatrix();
  body.inertia = rot *
                 Eigen::Vector3d(model->body_inertia[3], model->body_inertia[4], model->body_inertia[5]).asDiagonal() *
                 rot.transpose();
  mj_deleteModel(model);
  return body;
}

UnitInertia HullInertia(const std::vector<Eigen::Vector3d>& vertices) {
  const CompiledBody hull = CompileHull(vertices);
  UnitInertia u;
  u.centre = hull.centre;
  u.per_kg = hull.inertia / hull.mass;
  return u;
}

// Mesh objects: the file's vertices scaled, centred on their bounding box.
std::vector<Eigen::Vector3d> CentredMeshVertices(const ObjectConfig& object) {
  const MeshFile mesh = ReadMeshFile(object.mesh);
  const double scale = object.scale.value_or(1.0);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    lo = lo.cwiseMin(v * scale);
    hi = hi.cwiseMax(v * scale);
  }
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  std::vector<Eigen::Vector3d> out;
  out.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices) out.push_back(v * scale - centre);
  // STL repeats shared vertices once per triangle: MuJoCo hulls the same points either way, but the
  // model text is shorter without the repeats.
  std::sort(out.begin(), out.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace

Eigen::Vector3d MassProperties::PrincipalMomentsKgM2() const {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(inertia_kg_m2);
  return solver.eigenvalues();  // ascending
}

double LiquidMassKg(const ObjectConfig& object) {
  if (object.shape != ObjectShape::kBottle || !object.fill_fraction) return 0.0;
  const double inner_radius = 0.5 * object.size_m[0] - kBottleWallM;
  const double inner_height = kBottleBodyShare * object.size_m[2] - 2.0 * kBottleWallM;
  return kLiquidDensityKgM3 * kPi * inner_radius * inner_radius * inner_height * *object.fill_fraction;
}

std::vector<ObjectPart> ObjectParts(const ObjectConfig& object) {
  using Type = ObjectPart::Type;
  const auto& s = object.size_m;
  const double m = object.mass_kg;
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::vector<ObjectPart> parts;
  switch (object.shape) {
    case ObjectShape::kBox:
      parts.push_back(Primitive(Type::kBox, "body", {0.5 * s[0], 0.5 * s[1], 0.5 * s[2]}, origin, m));
      break;
    case ObjectShape::kCylinder:
      parts.push_back(Primitive(Type::kCylinder, "body", {0.5 * s[0], 0.5 * s[2], 0.0}, origin, m));
      break;
    case ObjectShape::kSphere:
      parts.push_back(Primitive(Type::kSphere, "body", {0.5 * s[0], 0.0, 0.0}, origin, m));
      break;
    case ObjectShape::kMug: {
      // Body: a cylinder about z; handle: two arms along +y and a grip, capsules, at +-H/4.
      const double radius = 0.5 * s[0], height = s[2], reach = s[1] - s[0];
      const double rh = kMugHandleRadiusM;
      const double grip_y = radius + reach - rh, arm_z = 0.25 * height;
      const double wall_volume = kPi * (Square(radius) - Square(radius - kMugWallM)) * height +
                                 kPi * Square(radius - kMugWallM) * kMugWallM;
      const double arm_length = grip_y - (radius - rh), grip_length = 2.0 * arm_z;
      const double handle_volume = kPi * rh * rh * (grip_length + 2.0 * arm_length);
      const double handle_kg = m * handle_volume / (wall_volume + handle_volume);
      const double per_m = handle_kg / (grip_length + 2.0 * arm_length);
      parts.push_back(Primitive(Type::kCylinder, "body", {radius, 0.5 * height, 0.0}, origin, m - handle_kg));
      parts.push_back(Capsule("handle grip", {0.0, grip_y, -arm_z}, {0.0, grip_y, arm_z}, rh, per_m * grip_length));
      for (const double z : {arm_z, -arm_z}) {
        parts.push_back(
            Capsule(z > 0 ? "handle upper arm" : "handle lower arm", {0.0, radius - rh, z}, {0.0, grip_y, z}, rh,
                    per_m * arm_length));
      }
      break;
    }
    case ObjectShape::kBottle: {
      const double radius = 0.5 * s[0], neck = 0.5 * s[1], height = s[2];
      const double bottom = -0.5 * height;
      const double body_top = bottom + kBottleBodyShare * height;
      const double shoulder_top = bottom + kBottleShoulderShare * height;
      const double liquid_kg = LiquidMassKg(object);
      const double shell_kg = m - liquid_kg;
      if (!(shell_kg > 0.0)) {
        std::ostringstream why;
        why << "object.fill_fraction = " << object.fill_fraction.value_or(0.0) << ": the liquid alone weighs "
            << liquid_kg << " kg, object.mass_kg is " << m << " kg (the total, bottle and liquid)";
        throw std::invalid_argument(why.str());
      }
      // A thin plastic shell: its mass follows the lateral areas.
      const double body_area = 2 * kPi * radius * (body_top - bottom) + kPi * radius * radius;
      const double shoulder_area =
          kPi * (radius + neck) * std::hypot(radius - neck, shoulder_top - body_top);
      const double neck_area = 2 * kPi * neck * (0.5 * height - shoulder_top);
      const double total_area = body_area + shoulder_area + neck_area;
      parts.push_back(Primitive(Type::kCylinder, "body", {radius, 0.5 * (body_top - bottom), 0.0},
                                {0.0, 0.0, 0.5 * (bottom + body_top)}, shell_kg * body_area / total_area));
      parts.push_back(
          Revolution("shoulder", {{{radius, body_top}, {neck, shoulder_top}}}, shell_kg * shoulder_area / total_area));
      parts.push_back(Primitive(Type::kCylinder, "neck", {neck, 0.5 * (0.5 * height - shoulder_top), 0.0},
                                {0.0, 0.0, 0.5 * (shoulder_top + 0.5 * height)}, shell_kg * neck_area / total_area));
      if (liquid_kg > 0.0) {
        const double inner_radius = radius - kBottleWallM;
        const double level = (body_top - bottom - 2.0 * kBottleWallM) * *object.fill_fraction;
        ObjectPart liquid = Primitive(Type::kCylinder, "liquid", {inner_radius, 0.5 * level, 0.0},
                                      {0.0, 0.0, bottom + kBottleWallM + 0.5 * level}, liquid_kg);
        liquid.collides = false;
        parts.push_back(liquid);
      }
      break;
    }
    case ObjectShape::kCup:
      parts.push_back(Revolution("body", {{{0.5 * s[1], -0.5 * s[2]}, {0.5 * s[0], 0.5 * s[2]}}}, m));
      break;
    case ObjectShape::kWineGlass: {
      const double bowl = 0.5 * s[0], foot = 0.5 * s[1], height = s[2], bottom = -0.5 * height;
      const double bowl_start = bottom + kGlassBowlStartShare * height;
      const double foot_top = bottom + kGlassFootThicknessM;
      parts.push_back(Revolution("bowl",
                                 {{{0.006, bowl_start},
                                   {0.85 * bowl, bottom + 0.62 * height},
                                   {bowl, bottom + 0.82 * height},
                                   {bowl, 0.5 * height}}},
                                 kGlassBowlShare * m));
      parts.push_back(Primitive(Type::kCylinder, "stem", {kGlassStemRadiusM, 0.5 * (bowl_start - foot_top), 0.0},
                                {0.0, 0.0, 0.5 * (bowl_start + foot_top)}, kGlassStemShare * m));
      parts.push_back(Primitive(Type::kCylinder, "foot", {foot, 0.5 * kGlassFootThicknessM, 0.0},
                                {0.0, 0.0, bottom + 0.5 * kGlassFootThicknessM},
                                (1.0 - kGlassBowlShare - kGlassStemShare) * m));
      break;
    }
    case ObjectShape::kEgg: {
      // Two half-ellipses meeting at the equator: the blunt end down, the pointed end up.
      const double radius = 0.5 * s[0], height = s[2], bottom = -0.5 * height;
      const double equator = bottom + kEggEquatorShare * height;
      const double below = equator - bottom, above = 0.5 * height - equator;
      std::vector<std::array<double, 2>> profile;
      for (int k = 0; k <= kEggRingsPerHalf; ++k) {
        const double phi = 0.5 * kPi * k / kEggRingsPerHalf;
        profile.push_back({radius * std::sin(phi), equator - below * std::cos(phi)});
      }
      for (int k = 1; k <= kEggRingsPerHalf; ++k) {
        const double phi = 0.5 * kPi * k / kEggRingsPerHalf;
        profile.push_back({radius * std::cos(phi), equator + above * std::sin(phi)});
      }
      parts.push_back(Revolution("shell", profile, m));
      break;
    }
    case ObjectShape::kBanana: {
      // A circular arc in the table's plane: its middle at the origin, the chord along y, bowed
      // towards -x (the finger's side); capsules of the banana's thickness between its points.
      const double chord = s[0], radius = 0.5 * s[1], sagitta = s[2];
      const double arc_radius = (0.25 * chord * chord + sagitta * sagitta) / (2.0 * sagitta);
      const double half_angle = std::asin(0.5 * chord / arc_radius);
      std::vector<Eigen::Vector3d> points;
      for (int k = 0; k <= kBananaSegments; ++k) {
        const double a = -half_angle + 2.0 * half_angle * k / kBananaSegments;
        points.emplace_back(arc_radius * (1.0 - std::cos(a)), arc_radius * std::sin(a), 0.0);
      }
      for (int k = 0; k < kBananaSegments; ++k) {
        parts.push_back(Capsule("segment " + std::to_string(k + 1), points[k], points[k + 1], radius,
                                m / kBananaSegments));
      }
      break;
    }
    case ObjectShape::kMesh: {
      ObjectPart part;
      part.type = Type::kMesh;
      part.role = "mesh (convex hull)";
      part.vertices_m = CentredMeshVertices(object);
      part.mass_kg = m;
      parts.push_back(std::move(part));
      break;
    }
  }
  return parts;
}

MassProperties ComputeMassProperties(const std::vector<ObjectPart>& parts) {
  MassProperties props;
  std::vector<UnitInertia> units;
  for (const ObjectPart& part : parts) {
    units.push_back(PartInertia(part));
    props.mass_kg += part.mass_kg;
    props.centre_of_mass_m += part.mass_kg * units.back().centre;
  }
  if (props.mass_kg > 0.0) props.centre_of_mass_m /= props.mass_kg;
  for (size_t k = 0; k < parts.size(); ++k) {
    const Eigen::Vector3d d = units[k].centre - props.centre_of_mass_m;
    props.inertia_kg_m2 += parts[k].mass_kg * (units[k].per_kg + d.squaredNorm() * Eigen::Matrix3d::Identity() -
                                               d * d.transpose());
  }
  return props;
}

std::optional<RoundSection> PinchRoundSection(const ObjectConfig& object) {
  const std::array<double, 3>& s = object.size_m;
  switch (object.shape) {
    case ObjectShape::kSphere:
      return RoundSection{Eigen::Vector3d::Zero(), 0.5 * s[0], "its centre"};
    case ObjectShape::kEgg:
      return RoundSection{Eigen::Vector3d(0.0, 0.0, (kEggEquatorShare - 0.5) * s[2]), 0.5 * s[0], "its equator"};
    case ObjectShape::kBanana: {
      // Across the middle capsule (ObjectParts): with an odd number of segments y = 0 falls at the
      // middle of a chord, which lies R (1 - cos(half angle / segments)) towards +x of the arc's middle.
      const double chord = s[0], sagitta = s[2];
      const double arc_radius = (0.25 * chord * chord + sagitta * sagitta) / (2.0 * sagitta);
      const double half_angle = std::asin(0.5 * chord / arc_radius);
      const double offset =
          kBananaSegments % 2 == 1 ? arc_radius * (1.0 - std::cos(half_angle / kBananaSegments)) : 0.0;
      return RoundSection{Eigen::Vector3d(offset, 0.0, 0.0), 0.5 * s[1], "its middle, across its thickness"};
    }
    default:
      return std::nullopt;
  }
}

double MeshFile::SignedVolume() const {
  double six_volume = 0.0;
  for (const auto& t : triangles) six_volume += vertices[t[0]].dot(vertices[t[1]].cross(vertices[t[2]]));
  return six_volume / 6.0;
}

namespace {

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

[[noreturn]] void BadMesh(const std::string& path, const std::string& why) {
  throw std::invalid_argument("object.mesh " + path + ": " + why);
}

MeshFile ReadStl(const std::string& path, const std::string& bytes) {
  MeshFile mesh;
  // Binary: 80-byte header, uint32 count, 50 bytes per triangle. A binary file may also begin with
  // "solid", so the size decides.
  if (bytes.size() >= 84) {
    uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);
    if (bytes.size() == 84 + 50ull * count) {
      for (uint32_t t = 0; t < count; ++t) {
        const char* at = bytes.data() + 84 + 50ull * t + 12;  // skip the normal
        std::array<int, 3> tri{};
        for (int k = 0; k < 3; ++k) {
          float xyz[3];
          std::memcpy(xyz, at + 12 * k, 12);
          if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2]))
            BadMesh(path, "triangle " + std::to_string(t + 1) + " has a vertex that is not a finite number");
          tri[k] = static_cast<int>(mesh.vertices.size());
          mesh.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
        }
        mesh.triangles.push_back(tri);
      }
      if (count == 0) BadMesh(path, "a binary STL with no triangles");
      return mesh;
    }
  }
  if (bytes.rfind("solid", 0) != 0) {
    if (bytes.size() >= 84) {
      uint32_t count = 0;
      std::memcpy(&count, bytes.data() + 80, 4);
      BadMesh(path, "not an STL: a binary STL of " + std::to_string(count) + " triangles has " +
                        std::to_string(84 + 50ull * count) + " bytes, this file " + std::to_string(bytes.size()) +
                        " (truncated or not a mesh), and it does not begin with \"solid\" (ASCII STL)");
    }
    BadMesh(path, "not an STL: " + std::to_string(bytes.size()) + " bytes, shorter than a binary STL's header");
  }
  std::istringstream in(bytes);
  std::string word;
  std::array<int, 3> tri{};
  int corner = 0;
  while (in >> word) {
    if (word != "vertex") continue;
    Eigen::Vector3d v;
    if (!(in >> v.x() >> v.y() >> v.z()) || !v.allFinite())
      BadMesh(path, "ASCII STL: vertex " + std::to_string(mesh.vertices.size() + 1) + " is not three numbers");
    tri[corner++] = static_cast<int>(mesh.vertices.size());
    mesh.vertices.push_back(v);
    if (corner == 3) {
      mesh.triangles.push_back(tri);
      corner = 0;
    }
  }
  if (corner != 0) BadMesh(path, "ASCII STL: the last facet has " + std::to_string(corner) + " vertices, not 3");
  if (mesh.triangles.empty()) BadMesh(path, "ASCII STL with no facets");
  return mesh;
}

MeshFile ReadObj(const std::string& path, const std::string& bytes) {
  MeshFile mesh;
  std::istringstream in(bytes);
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream fields(line);
    std::string kind;
    fields >> kind;
    if (kind == "v") {
      Eigen::Vector3d v;
      if (!(fields >> v.x() >> v.y() >> v.z()) || !v.allFinite())
        BadMesh(path, "line " + std::to_string(line_number) + ": a vertex needs three numbers");
      mesh.vertices.push_back(v);
    } else if (kind == "f") {
      std::vector<int> corners;
      std::string corner;
      while (fields >> corner) {
        const int index = std::atoi(corner.c_str());  // "7/3/2" -> 7
        const int resolved = index < 0 ? static_cast<int>(mesh.vertices.size()) + index : index - 1;
        if (index == 0 || resolved < 0 || resolved >= static_cast<int>(mesh.vertices.size()))
          BadMesh(path, "line " + std::to_string(line_number) + ": face vertex " + corner + " does not exist");
        corners.push_back(resolved);
      }
      for (size_t k = 2; k < corners.size(); ++k) mesh.triangles.push_back({corners[0], corners[k - 1], corners[k]});
    }
  }
  if (mesh.vertices.size() < 4) BadMesh(path, "OBJ with " + std::to_string(mesh.vertices.size()) + " vertices");
  return mesh;
}

}  // namespace

MeshFile ReadMeshFile(const std::string& path) {
  const std::string extension = Lower(path.size() >= 4 ? path.substr(path.size() - 4) : "");
  if (extension != ".stl" && extension != ".obj") {
    BadMesh(path, "unsupported format: graspbed reads STL (.stl) and Wavefront OBJ (.obj); convert MuJoCo's "
                  ".msh or other formats to STL");
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) BadMesh(path, std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream content;
  content << file.rdbuf();
  const std::string bytes = content.str();
  if (bytes.empty()) BadMesh(path, "the file is empty");
  MeshFile mesh = extension == ".stl" ? ReadStl(path, bytes) : ReadObj(path, bytes);
  if (mesh.vertices.size() < 4) BadMesh(path, "fewer than 4 vertices");
  return mesh;
}

double ConvexHullVolume(const std::vector<Eigen::Vector3d>& points) { return CompileHull(points).mass; }

std::string MeshHullWarning(const std::string& path, double scale) {
  const MeshFile mesh = ReadMeshFile(path);
  std::vector<Eigen::Vector3d> scaled;
  for (const Eigen::Vector3d& v : mesh.vertices) scaled.push_back(v * scale);
  const double hull = ConvexHullVolume(scaled);
  const double enclosed = std::abs(mesh.SignedVolume()) * scale * scale * scale;
  std::ostringstream out;
  out << std::setprecision(4);
  if (enclosed <= 0.0) {
    out << "object.mesh " << path << ": MuJoCo collides and weighs its convex hull (" << hull * 1e6
        << " cm^3); the mesh encloses no volume (not a closed surface), so the hull may differ from it a lot";
    return out.str();
  }
  const double excess = hull / enclosed - 1.0;
  if (excess <= 0.01) return "";
  out << "object.mesh " << path << ": MuJoCo collides and weighs its convex hull, not the mesh: hull "
      << hull * 1e6 << " cm^3, mesh " << enclosed * 1e6 << " cm^3 (+" << std::setprecision(3) << excess * 100.0
      << " %): hollows and dents are filled, contacts land on the hull, and the mass spreads over it";
  return out.str();
}

}  // namespace graspbed::sim
