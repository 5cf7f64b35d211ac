#include "sim/scene_check.h"

#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace graspbed::sim {
namespace {

enum class Part { kObject, kTable, kHand };

// The deepest overlap found between two parts, with the geoms that make it.
struct Overlap {
  double depth_m = 0.0;
  int geom1 = -1;
  int geom2 = -1;
};

std::string Number(double value) { return FormatConfigNumber(value); }

std::string Triple(const std::array<double, 3>& values) { return FormatConfigTriple(values); }

std::string GeomName(const mjModel* m, int geom) {
  const char* name = mj_id2name(m, mjOBJ_GEOM, geom);
  return name != nullptr && name[0] != '\0' ? "'" + std::string(name) + "'" : "#" + std::to_string(geom);
}

std::string Describe(const mjModel* m, const char* what, const Overlap& overlap) {
  char depth[32];
  std::snprintf(depth, sizeof(depth), "%.2f", overlap.depth_m * 1e3);
  return std::string("scene: ") + what + " by " + depth + " mm at the start (geoms " +
         GeomName(m, overlap.geom1) + " and " + GeomName(m, overlap.geom2) + "; at most " +
         Number(kMaxInitialPenetrationM * 1e3) + " mm allowed): ";
}

}  // namespace

void CheckInitialPenetration(const Simulation& simulation) {
  const mjModel* m = simulation.model();
  const mjData* d = simulation.data();
  const int object_body = mj_name2id(m, mjOBJ_BODY, "object");
  const auto part_of = [&](int geom) {
    const int body = m->geom_bodyid[geom];
    if (body == object_body) return Part::kObject;
    if (body == 0) return Part::kTable;
    return Part::kHand;
  };
  Overlap object_hand;
  Overlap hand_table;
  Overlap object_table;
  for (int c = 0; c < d->ncon; ++c) {
    const mjContact& contact = d->contact[c];
    const double depth = -contact.dist;
    if (!(depth > kMaxInitialPenetrationM)) continue;
    const Part a = part_of(contact.geom1);
    const Part b = part_of(contact.geom2);
    if (a == b) continue;  // within the hand: the model's own business
    const bool has_object = a == Part::kObject || b == Part::kObject;
    const bool has_table = a == Part::kTable || b == Part::kTable;
    Overlap& overlap = has_object && has_table ? object_table : has_object ? object_hand : hand_table;
    if (depth > overlap.depth_m) overlap = {depth, contact.geom1, contact.geom2};
  }

  const SceneConfig& scene = simulation.scene();
  const std::string size = "object.size_m = " + Triple(scene.object.size_m);
  const std::string object_position =
      "object.initial_position_m = " + Triple(scene.object.initial_position_m);
  const std::string wrist = "hand.initial_wrist_position_m = " + Triple(scene.hand.initial_wrist_position_m);
  if (object_hand.geom1 >= 0) {
    // The pre-shape as the file gave it, or as it followed the object (open_gap_m absent = NaN).
    const std::string gap = std::isnan(scene.hand.open_gap_m)
                                ? "auto = " + Number(scene.OpenGapM()) +
                                      " m (the object's width plus 2 x "
                                      "hand.preshape_clearance_m = " +
                                      Number(scene.hand.preshape_clearance_m) + " m)"
                                : Number(scene.hand.open_gap_m) + " m";
    throw std::invalid_argument(
        Describe(m, "the object and the hand overlap", object_hand) + "the object (" + size + ", " +
        object_position + ") is not clear of the digits of the pre-shape " + "hand.open_gap_m = " + gap +
        " at " + wrist + "; a smaller object, a wider pre-shape or another position fixes it");
  }
  if (object_table.geom1 >= 0) {
    throw std::invalid_argument(Describe(m, "the object and the table overlap", object_table) +
                                object_position + " puts the object into the table (with " + size +
                                "); give z < 0 to rest it on the table, or z at least its half height");
  }
  if (hand_table.geom1 >= 0) {
    throw std::invalid_argument(
        Describe(m, "the hand and the table overlap", hand_table) + wrist +
        " (auto: the fingertip pad at the pinch height, set by " + size + " and " + object_position +
        ") puts the hand into the table; raise hand.initial_wrist_position_m[2] or use a taller object");
  }
}

}  // namespace graspbed::sim
