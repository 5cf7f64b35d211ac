// Contact mapping through the whole sensor path: a flat plate pressed onto one column of mesas with
// a known force, then sheared along the holder axis. Forces are read back through the simulated
// backend, Readout and Inversion (not ground truth) and compared with the applied load.
//
// Setup: gravity off, no table, the prosthetic finger at its pre-shape held there by the grip brake. The
// holder is curved, so a plate pressed along the palmar axis would meet tilted mesas (about 12 deg at 2.5 mm
// of arc) and each would only see F cos(tilt); instead the plate is laid perpendicular to the inward normal
// of column 1 (arc -2.5 mm, units 1, 5, 9, 13, 17), touching exactly that column's five mesa tops, and pushed
// along that normal.
#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <mujoco/mujoco.h>

#include <array>
#include <cmath>
#include <vector>

#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/readout.h"
#include "sim/sim_backend.h"
#include "tests/sim/sim_fixture.h"

namespace graspbed::sim {
namespace {

constexpr double kRelativeForceTol = 0.02;  // 2 % at equilibrium: the inversion is exact for an ideal sensor,
                                            // so what is left is the contact model's force balance
constexpr double kUnsensedShearTolN = 0.01;
constexpr double kPressForceN = 5.0;
constexpr double kShearForceN = 1.0;
constexpr int kColumn = 1;
constexpr double kPlateHalfThicknessM = 1e-3;
constexpr double kPlateGapM = 0.05e-3;  // initial air gap above the mesa tops

class ContactMappingTest : public test_support::MujocoTest {
 protected:
  void SetUp() override {
    SceneConfig scene;
    scene.physics.gravity_m_s2 = 0.0;
    scene.physics.table = false;
    scene.object.shape = ObjectShape::kBox;
    scene.object.size_m = {0.03, 0.004, 2 * kPlateHalfThicknessM};  // local x along the holder axis
    scene.object.mass_kg = 0.01;
    scene.object.friction = 1.0;
    simulation_ = &MakeSimulation(DefaultLayout(), scene);
    simulation_->SetGripBrake(true);
    PlacePlate();
    backend_ = std::make_unique<SimBackend>(*simulation_, SimBackendConfig{}, 1);
    readout_ = std::make_unique<sensor::Readout>(sensor::ReadoutConfig{}, DefaultLayout().unit_count(),
                                                 backend_->nominal_r0_ohm());
    inversion_ = std::make_unique<sensor::Inversion>(
        DefaultLayout(), sensor::PaperCalibration(DefaultLayout().unit_count()), sensor::InversionConfig{});
    // Tare on unloaded frames.
    RunFor(0.2);
    ASSERT_TRUE(readout_->tared());
  }

  // Lays the plate flat on the mesa tops of column 1, centred on row 2, with an air gap.
  void PlacePlate() {
    const sensor::Layout& layout = DefaultLayout();
    const mjModel* m = simulation_->model();
    mjData* d = simulation_->mutable_data();
    const int holder = mj_name2id(m, mjOBJ_BODY, "holder");
    const mjtNum* rot = d->xmat + 9 * holder;  // holder -> world, row-major
    const sensor::UnitPose& unit = layout.units[2 * 4 + kColumn];
    auto to_world_dir = [&](const Eigen::Vector3d& v) {
      Eigen::Vector3d out;
      for (int r = 0; r < 3; ++r) out[r] = rot[3 * r] * v[0] + rot[3 * r + 1] * v[1] + rot[3 * r + 2] * v[2];
      return out;
    };
    const Eigen::Vector3d outward = to_world_dir(-unit.inward_normal);
    const Eigen::Vector3d axial = to_world_dir(Eigen::Vector3d::UnitX());
    inward_world_ = -outward;
    axial_world_ = axial;
    const Eigen::Vector3d surface =
        to_world_dir(unit.position_m) +
        Eigen::Vector3d(d->xpos[3 * holder], d->xpos[3 * holder + 1], d->xpos[3 * holder + 2]);
    const Eigen::Vector3d center =
        surface + outward * (layout.unit.mesa_height_m + kPlateHalfThicknessM + kPlateGapM);
    Eigen::Matrix3d plate_rot;
    plate_rot.col(0) = axial;
    plate_rot.col(2) = outward;
    plate_rot.col(1) = outward.cross(axial);
    const Eigen::Quaterniond q(plate_rot);
    const int qpos = m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, "object_free")];
    for (int k = 0; k < 3; ++k) d->qpos[qpos + k] = center[k];
    d->qpos[qpos + 3] = q.w();
    d->qpos[qpos + 4] = q.x();
    d->qpos[qpos + 5] = q.y();
    d->qpos[qpos + 6] = q.z();
    mj_forward(m, d);
  }

  void RunFor(double duration_s) {
    const double end = simulation_->time_s() + duration_s;
    while (simulation_->time_s() < end - 1e-9) {
      simulation_->Step();
      backend_->Poll(simulation_->time_s());
      if (backend_->Read(&frame_) == sensor::ReadStatus::kOk) {
        readout_->Process(frame_, &readout_frame_);
        inversion_->Invert(readout_frame_, &state_);
      }
    }
  }

  void Push(double normal_n, double axial_shear_n) {
    std::array<double, 3> force{};
    for (int k = 0; k < 3; ++k) force[k] = normal_n * inward_world_[k] + axial_shear_n * axial_world_[k];
    simulation_->SetObjectExternalForce(force);
  }

  static bool InColumn(int unit) { return unit % 4 == kColumn; }
  static bool Axial(int unit) {
    return DefaultLayout().units[unit].orientation == sensor::BeamOrientation::kAxial;
  }

  Simulation* simulation_ = nullptr;
  std::unique_ptr<SimBackend> backend_;
  std::unique_ptr<sensor::Readout> readout_;
  std::unique_ptr<sensor::Inversion> inversion_;
  sensor::RawFrame frame_;
  sensor::ReadoutFrame readout_frame_;
  sensor::TactileState state_;
  Eigen::Vector3d inward_world_;
  Eigen::Vector3d axial_world_;
};

TEST_F(ContactMappingTest, PressedPlateInvertsToTheAppliedNormalForce) {
  Push(kPressForceN, 0.0);
  RunFor(0.5);
  double sensed_fn = 0.0;
  int loaded = 0;
  for (int i = 0; i < state_.unit_count; ++i) {
    if (state_.fn_n[i] > 0.05) {
      sensed_fn += state_.fn_n[i];
      ++loaded;
      EXPECT_TRUE(InColumn(i)) << "unit " << i << " outside the pressed column reads " << state_.fn_n[i]
                               << " N";
    }
  }
  EXPECT_EQ(loaded, 5);
  EXPECT_NEAR(sensed_fn, kPressForceN, kRelativeForceTol * kPressForceN);
  EXPECT_NEAR(state_.total_fn_n, kPressForceN, kRelativeForceTol * kPressForceN);
  const GroundTruth truth = simulation_->truth();
  EXPECT_NEAR(truth.sensed_share, 1.0, 1e-9) << "a flat plate on the mesas loads only the mesas";
  EXPECT_LT(truth.max_mesa_penetration_m, 0.05e-3);
}

TEST_F(ContactMappingTest, AxialShearShowsOnAxialUnitsOnly) {
  Push(kPressForceN, kShearForceN);
  RunFor(0.5);
  const std::span<const sensor::UnitLoad> truth = backend_->last_loads();
  double axial_ft_truth = 0.0;
  double total_axial_shear_truth = 0.0;
  for (int i = 0; i < state_.unit_count; ++i) {
    if (!InColumn(i)) {
      EXPECT_NEAR(state_.ft_n[i], 0.0, kUnsensedShearTolN) << "unloaded unit " << i;
      continue;
    }
    if (Axial(i)) {
      // Beam along +x of the holder: the shear shows with its sign and size.
      EXPECT_GT(state_.ft_n[i], 0.05) << "unit " << i;
      EXPECT_NEAR(state_.ft_n[i], truth[i].ft_n, kRelativeForceTol * std::abs(truth[i].ft_n) + 1e-3)
          << "unit " << i;
      axial_ft_truth += truth[i].ft_n;
      total_axial_shear_truth += truth[i].ft_n;
    } else {
      // Beam around the circumference: the axial shear is across the beam, carried but not sensed.
      EXPECT_NEAR(state_.ft_n[i], 0.0, kUnsensedShearTolN) << "unit " << i;
      EXPECT_GT(std::abs(truth[i].cross_shear_n), 0.05)
          << "unit " << i << " should carry shear across its beam";
      // normal x beam for a circumferential beam points along -x or +x of the holder.
      const Eigen::Vector3d cross =
          DefaultLayout().units[i].inward_normal.cross(DefaultLayout().units[i].beam_axis);
      total_axial_shear_truth += truth[i].cross_shear_n * cross.x();
    }
  }
  // Every bit of the applied shear reaches the mesas, and the axial units' share is sensed.
  EXPECT_NEAR(total_axial_shear_truth, kShearForceN, kRelativeForceTol * kShearForceN);
  EXPECT_NEAR(state_.total_shear_axial_n, axial_ft_truth, kRelativeForceTol * axial_ft_truth);
  EXPECT_NEAR(state_.total_fn_n, kPressForceN, kRelativeForceTol * kPressForceN);
}

TEST_F(ContactMappingTest, ReversedShearReversesTheSign) {
  Push(kPressForceN, -kShearForceN);
  RunFor(0.5);
  for (int i = 0; i < state_.unit_count; ++i) {
    if (InColumn(i) && Axial(i)) {
      EXPECT_LT(state_.ft_n[i], -0.05) << "unit " << i;
    }
  }
  EXPECT_LT(state_.total_shear_axial_n, -0.2);
}

}  // namespace
}  // namespace graspbed::sim
