#pragma once
/// The geometry and mass distribution of the graspable object: the parts (MuJoCo geoms) an
/// ObjectConfig is made of, their masses, and the compound's mass, centre of mass and inertia
/// computed here independently of MuJoCo (for `graspbed objects`, docs and the tests that hold the
/// compiled model to them). Docs: docs/scenarios.md, "Object library".
///
/// Object frame (the body "object"): origin at the centre of the object's bounding box across the
/// grasp and along z (a mug's body axis, its handle off to +y), z up when the object stands as it
/// rests on the table, the pinch along x. Every part is convex, as MuJoCo 2.2.2 collides a mesh by its
/// convex hull: a surface of revolution is cut into convex pieces where its profile turns inwards.

#include <Eigen/Core>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/scene_config.h"

namespace graspbed::sim {

/// Density of the liquid in a part-filled container (water) [kg/m^3].
inline constexpr double kLiquidDensityKgM3 = 1000.0;
/// Sides of the polygons that stand for the circles of a mesh part's rings [-].
inline constexpr int kRevolutionSegments = 32;

/// One geom of the object, object frame.
struct ObjectPart {
  enum class Type { kBox, kCylinder, kSphere, kCapsule, kMesh };
  Type type = Type::kBox;
  std::string role;  ///< what it is ("body", "handle grip", "liquid"), for listings and tests
  /// MuJoCo size: box half extents [m]; cylinder / capsule radius, half length [m]; sphere radius.
  std::array<double, 3> size_m{};
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< part centre, object frame [m]
  /// Part axis (cylinder, capsule: its length) as a unit vector in the object frame.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  /// kMesh: the vertices, object frame [m] (MuJoCo takes their convex hull).
  std::vector<Eigen::Vector3d> vertices_m;
  /// kMesh built from a profile: the revolution about z it was made from, (radius, z) pairs [m],
  /// for the analytic inertia (empty for a user's mesh).
  std::vector<std::array<double, 2>> profile_m;
  double mass_kg = 0.0;  ///< [kg]
  bool collides = true;  ///< false: mass only (the liquid inside a container)
};

/// Mass, centre of mass and inertia of a set of parts.
struct MassProperties {
  double mass_kg = 0.0;                                        ///< [kg]
  Eigen::Vector3d centre_of_mass_m = Eigen::Vector3d::Zero();  ///< object frame [m]
  /// Inertia about the centre of mass, object axes [kg m^2].
  Eigen::Matrix3d inertia_kg_m2 = Eigen::Matrix3d::Zero();
  /// Principal moments, ascending [kg m^2].
  Eigen::Vector3d PrincipalMomentsKgM2() const;
};

/// The parts of `object` (shapes box, cylinder and sphere: one part, as the model always had),
/// their masses summing to object.mass_kg. Mesh objects read their file (ReadMeshFile).
/// @throws std::invalid_argument when the object cannot be built (a filled container whose liquid
///   outweighs its mass_kg, a mesh file that cannot be read).
std::vector<ObjectPart> ObjectParts(const ObjectConfig& object);

/// Mass properties of `parts`, each part a uniform solid of its shape: closed forms for the
/// primitives, the exact polygonal frustums of a revolution profile, the convex hull's tetrahedra
/// for a user's mesh.
MassProperties ComputeMassProperties(const std::vector<ObjectPart>& parts);

/// A section of the object that is round in the pinch's plane (world x-z at its start pose), which a
/// pinch grips through its centre: a ball's great circle, an egg's equator (its profile's widest
/// ring; the profile's curvature there is the egg's, approximated by the circle), a banana's middle
/// across its thickness.
struct RoundSection {
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();  ///< object frame [m]
  double radius_m = 0.0;                               ///< [m]
  const char* where = "";                              ///< "its centre", "its equator", ...
};

/// The round section a pinch takes `object` by, or nullopt for an object pinched by its faces.
std::optional<RoundSection> PinchRoundSection(const ObjectConfig& object);

/// Mass of the liquid in a part-filled container (bottle), 0 for everything else [kg].
double LiquidMassKg(const ObjectConfig& object);

/// A triangle mesh read from a file, in the file's units (before scale).
struct MeshFile {
  std::vector<Eigen::Vector3d> vertices;       ///< as read (STL: 3 per triangle, shared ones repeated)
  std::vector<std::array<int, 3>> triangles;   ///< indices into vertices
  /// Volume enclosed by the triangles (divergence theorem; meaningful for a closed surface) [file unit^3].
  double SignedVolume() const;
};

/// Reads a binary or ASCII STL, or the vertices and faces of a Wavefront OBJ (the formats MuJoCo
/// 2.2.2 reads besides its own MSH).
/// @throws std::invalid_argument naming the file and what is wrong (missing, empty, truncated, not
///   a mesh, an unsupported extension).
MeshFile ReadMeshFile(const std::string& path);

/// Volume of the convex hull of `points` [unit^3] (MuJoCo collides and weighs a mesh by its hull),
/// computed by MuJoCo itself: the hull of a mesh of density 1.
/// @throws std::invalid_argument when MuJoCo refuses the points (fewer than 4, all in a plane).
double ConvexHullVolume(const std::vector<Eigen::Vector3d>& points);

/// "object.mesh FILE: MuJoCo collides and weighs its convex hull, not the mesh: hull X cm^3, mesh Y
/// cm^3 (+Z %)" when the hull is more than 1 % larger than the mesh, else "".
std::string MeshHullWarning(const std::string& path, double scale);

}  // namespace graspbed::sim
