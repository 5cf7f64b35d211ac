#include "sim/hand_kinematics.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <stdexcept>
#include <string>

namespace graspbed::sim {
namespace {

// Index segments point along d(phi) = (-cos phi, -sin phi) in (x, z): phi = 0 straight out from the
// palm away from the thumb, pi/2 straight down; the palmar side faces n(phi) = (sin phi, -cos phi).
Eigen::Vector2d IndexDirection(double phi) { return {-std::cos(phi), -std::sin(phi)}; }
Eigen::Vector2d IndexPalmar(double phi) { return {std::sin(phi), -std::cos(phi)}; }
// The thumb mirrors it: (cos a, -sin a), a = 0 straight out towards +x, pi/2 straight down.
Eigen::Vector2d ThumbDirection(double alpha) { return {std::cos(alpha), -std::sin(alpha)}; }

// Root of the increasing (sign = +1) or decreasing (sign = -1) function f on [lo, hi], clamped.
double Bisect(const std::function<double(double)>& f, double target, double lo, double hi, double sign) {
  if (sign * (f(lo) - target) >= 0.0) return lo;
  if (sign * (f(hi) - target) <= 0.0) return hi;
  for (int i = 0; i < 80; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (sign * (f(mid) - target) < 0.0) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

}  // namespace

ProstheticKinematics::ProstheticKinematics(const FingerConfig& finger, const ThumbConfig& thumb,
                                           double holder_length_m, double holder_half_depth_m,
                                           double mesa_height_m)
    : finger_(finger),
      thumb_(thumb),
      holder_length_m_(holder_length_m),
      pad_depth_m_(holder_half_depth_m + mesa_height_m) {
  // Nominal pinch: the distal phalanx points straight down, so the pad meets a vertical face squarely.
  const double ratio = 1.0 + finger_.pip_mcp_ratio;
  const double mcp_nominal =
      (0.5 * std::numbers::pi - finger_.dip_flexion_rad - finger_.mcp_rest_angle_rad) / ratio;
  if (!(mcp_nominal > kMcpMinRad && mcp_nominal < kMcpMaxRad)) {
    throw std::invalid_argument("hand.finger: the pad cannot meet an object squarely (MCP would need " +
                                std::to_string(mcp_nominal) +
                                " rad); check dip_flexion_rad, mcp_rest_angle_rad");
  }
  // Place the MCP so that the square pad sits at x = -nominal/2, and the thumb base so that its tip
  // meets the object's other face at the same height.
  mcp_ = {0.0, -kPalmDepthM};
  const DigitContact pad = IndexPad(mcp_nominal);
  mcp_.x() = -0.5 * kNominalWidthM - pad.point_xz.x();
  const double pad_z = pad.point_xz.y();
  const double thumb_nominal = 0.5 * std::numbers::pi + kThumbLeanRad - thumb_.ip_flexion_rad;
  thumb_base_ = {0.0, 0.0};
  const DigitContact tip = ThumbTip(thumb_nominal);
  thumb_base_ = {0.5 * kNominalWidthM - tip.point_xz.x(), pad_z - tip.point_xz.y()};
}

Eigen::Vector2d ProstheticKinematics::Pip(double mcp_rad) const {
  return mcp_ + finger_.proximal_length_m * IndexDirection(finger_.mcp_rest_angle_rad + mcp_rad);
}

Eigen::Vector2d ProstheticKinematics::Dip(double mcp_rad) const {
  const double middle = finger_.mcp_rest_angle_rad + (1.0 + finger_.pip_mcp_ratio) * mcp_rad;
  return Pip(mcp_rad) + finger_.middle_length_m * IndexDirection(middle);
}

double ProstheticKinematics::DistalAngle(double mcp_rad) const {
  return finger_.mcp_rest_angle_rad + (1.0 + finger_.pip_mcp_ratio) * mcp_rad + finger_.dip_flexion_rad;
}

DigitContact ProstheticKinematics::IndexPad(double mcp_rad) const {
  const double distal = DistalAngle(mcp_rad);
  DigitContact contact;
  contact.point_xz =
      Dip(mcp_rad) + 0.5 * holder_length_m_ * IndexDirection(distal) + pad_depth_m_ * IndexPalmar(distal);
  contact.normal_angle_rad = distal - 0.5 * std::numbers::pi;
  return contact;
}

Eigen::Vector2d ProstheticKinematics::ThumbIp(double flexion_rad) const {
  return thumb_base_ + thumb_.proximal_length_m * ThumbDirection(flexion_rad);
}

Eigen::Vector2d ProstheticKinematics::ThumbTipCentre(double flexion_rad) const {
  return ThumbIp(flexion_rad) + thumb_.distal_length_m * ThumbDirection(flexion_rad + thumb_.ip_flexion_rad);
}

DigitContact ProstheticKinematics::ThumbTip(double flexion_rad) const {
  DigitContact contact;
  contact.point_xz = ThumbTipCentre(flexion_rad) - Eigen::Vector2d(thumb_.tip_radius_m, 0.0);
  contact.normal_angle_rad = std::numbers::pi;
  return contact;
}

double ProstheticKinematics::McpForPadX(double x_m) const {
  return Bisect([this](double q) { return IndexPad(q).point_xz.x(); }, x_m, kMcpMinRad, kMcpMaxRad, 1.0);
}

double ProstheticKinematics::ThumbForTipX(double x_m) const {
  return Bisect([this](double q) { return ThumbTip(q).point_xz.x(); }, x_m, kThumbMinRad, kThumbMaxRad, -1.0);
}

double ProstheticKinematics::PadLeverArmM(double mcp_rad) const {
  constexpr double kStep = 1e-6;
  return (IndexPad(mcp_rad + kStep).point_xz.x() - IndexPad(mcp_rad - kStep).point_xz.x()) / (2.0 * kStep);
}

double ProstheticKinematics::ThumbLeverArmM(double flexion_rad) const {
  constexpr double kStep = 1e-6;
  return (ThumbTip(flexion_rad - kStep).point_xz.x() - ThumbTip(flexion_rad + kStep).point_xz.x()) /
         (2.0 * kStep);
}

double ProstheticKinematics::MaxApertureM() const {
  return ThumbTip(kThumbMinRad).point_xz.x() - IndexPad(kMcpMinRad).point_xz.x();
}

}  // namespace graspbed::sim
