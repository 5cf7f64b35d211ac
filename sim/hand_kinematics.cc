#include "sim/hand_kinematics.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
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

// Closest point of segment [a, b] to p.
Eigen::Vector2d ClosestOnSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                                 const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return a + t * ab;
}

// Distance from a circle (centre c, radius r) to a capsule (axis [a, b], radius rc); < 0 overlaps.
double CapsuleClearance(const Eigen::Vector2d& c, double r, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b, double rc) {
  return (c - ClosestOnSegment(c, a, b)).norm() - r - rc;
}

// The first q from `from` towards `to` (stepping `step`) at which f(q) <= 0, refined by bisection;
// NaN when f stays positive all the way.
double FirstRoot(const std::function<double(double)>& f, double from, double to, double step) {
  const double direction = to > from ? 1.0 : -1.0;
  double previous = from;
  for (double q = from; direction * (to - q) > -1e-12; q += direction * step) {
    const double clamped = direction > 0.0 ? std::min(q, to) : std::max(q, to);
    if (f(clamped) <= 0.0) {
      if (clamped == from) return from;
      double lo = previous;  // f > 0
      double hi = clamped;   // f <= 0
      for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        (f(mid) > 0.0 ? lo : hi) = mid;
      }
      return hi;
    }
    previous = clamped;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// In a wrap the pad's normal points at least this far from H +x towards the palm (+z) [rad]: it
// presses the cylinder against the palm rather than across it (sin 30 deg: half its force).
constexpr double kMinWrapPadNormalRad = std::numbers::pi / 6.0;
// Angular step of the scans above [rad]: finer than any link's travel across a clearance of 1 mm.
constexpr double kScanStepRad = 0.005;
// When the pad touches the cylinder the proximal and middle phalanges are at most kWrapLinkContactM
// from it if the pad's contact can move that far towards the DIP (kWrapMaxAlongPadM, the first mesa
// row, in kWrapAlongStepM steps), and never closer than kMinLinkClearanceM (overlapping it) [m].
constexpr double kWrapLinkContactM = 1.0e-3;
constexpr double kWrapMaxAlongPadM = 0.010;
constexpr double kWrapAlongStepM = 0.0005;
constexpr double kMinLinkClearanceM = -0.5e-3;

}  // namespace

ProstheticKinematics::ProstheticKinematics(const FingerConfig& finger, const ThumbConfig& thumb,
                                           double holder_length_m, double holder_half_depth_m,
                                           double mesa_height_m)
    : finger_(finger),
      thumb_(thumb),
      holder_length_m_(holder_length_m),
      pad_depth_m_(holder_half_depth_m + mesa_height_m) {
  // Nominal pinch: the distal phalanx points straight down, so the pad meets a vertical face squarely.
  const double mcp_nominal = SquarePadMcpRad();
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

double ProstheticKinematics::SquarePadMcpRad() const {
  return (0.5 * std::numbers::pi - finger_.dip_flexion_rad - finger_.mcp_rest_angle_rad) /
         (1.0 + finger_.pip_mcp_ratio);
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

DigitContact ProstheticKinematics::IndexPadAt(double mcp_rad, double along_m) const {
  DigitContact contact = IndexPad(mcp_rad);
  contact.point_xz += along_m * IndexDirection(DistalAngle(mcp_rad));
  return contact;
}

RoundPinchPose ProstheticKinematics::RoundPinch(double radius_m, double along_m) const {
  // The thumb tip's centre must sit on the pad's normal through the section's centre, the tip's
  // radius beyond the section: residual(mcp, thumb) = 0, two equations in two angles.
  const auto residual = [&](double mcp, double thumb) {
    const DigitContact pad = IndexPadAt(mcp, along_m);
    const Eigen::Vector2d normal(std::cos(pad.normal_angle_rad), std::sin(pad.normal_angle_rad));
    return Eigen::Vector2d(ThumbTipCentre(thumb) - pad.point_xz - (2.0 * radius_m + thumb_.tip_radius_m) * normal);
  };
  double mcp = SquarePadMcpRad();
  double thumb = ThumbForTipX(IndexPadAt(mcp, along_m).point_xz.x() + 2.0 * radius_m);
  constexpr double kStep = 1e-7;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Eigen::Vector2d r = residual(mcp, thumb);
    if (r.norm() < 1e-9) break;
    Eigen::Matrix2d jacobian;
    jacobian.col(0) = (residual(mcp + kStep, thumb) - residual(mcp - kStep, thumb)) / (2.0 * kStep);
    jacobian.col(1) = (residual(mcp, thumb + kStep) - residual(mcp, thumb - kStep)) / (2.0 * kStep);
    const Eigen::Vector2d delta = jacobian.partialPivLu().solve(-r);
    // Damped: no step beyond 0.1 rad, so the iteration stays on the branch it starts on.
    const double scale = std::min(1.0, 0.1 / std::max(std::abs(delta.x()), std::abs(delta.y())));
    mcp += scale * delta.x();
    thumb += scale * delta.y();
  }
  std::ostringstream why;
  if (residual(mcp, thumb).norm() > 1e-6 || !std::isfinite(mcp) || !std::isfinite(thumb)) {
    why << "no posture puts the pad and the thumb on one line through its centre";
  } else if (mcp < kMcpMinRad || mcp > kMcpMaxRad || thumb < kThumbMinRad || thumb > kThumbMaxRad) {
    why << "the pinch through its centre needs MCP " << mcp * 180.0 / std::numbers::pi << " deg and thumb "
        << thumb * 180.0 / std::numbers::pi << " deg, beyond the joints' ranges";
  }
  if (!why.str().empty()) {
    std::ostringstream message;
    message << "a pinch of a " << 2e3 * radius_m << " mm round section: " << why.str();
    throw std::invalid_argument(message.str());
  }
  RoundPinchPose pose;
  pose.mcp_rad = mcp;
  pose.thumb_rad = thumb;
  const DigitContact pad = IndexPadAt(mcp, along_m);
  const Eigen::Vector2d normal(std::cos(pad.normal_angle_rad), std::sin(pad.normal_angle_rad));
  pose.pad_contact_xz = pad.point_xz;
  pose.centre_xz = pad.point_xz + radius_m * normal;
  pose.thumb_contact_xz = pose.centre_xz + radius_m * normal;
  pose.line_angle_rad = pad.normal_angle_rad;
  // The holder's side in the x-z plane reaches pad_depth either side of its axis; its rounded tip is
  // half an ellipse (semi-axes the cap's length along the axis, pad_depth across) beyond its end.
  const Eigen::Vector2d along = IndexDirection(DistalAngle(mcp));
  const Eigen::Vector2d across = IndexPalmar(DistalAngle(mcp));
  const Eigen::Vector2d holder_end = Dip(mcp) + holder_length_m_ * along;
  const double side = pad_depth_m_ * std::abs(across.y());
  const double cap = std::hypot(kTipCapLengthM * along.y(), pad_depth_m_ * across.y());
  pose.lowest_z_m = std::min({Dip(mcp).y() - side, holder_end.y() - side, holder_end.y() - cap,
                              ThumbTipCentre(thumb).y() - thumb_.tip_radius_m});
  return pose;
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

double ProstheticKinematics::IndexClearanceM(double mcp_rad, const Eigen::Vector2d& centre_xz,
                                             double radius_m, bool links_only) const {
  const Eigen::Vector2d pip = Pip(mcp_rad);
  const Eigen::Vector2d dip = Dip(mcp_rad);
  double clearance = std::min(CapsuleClearance(centre_xz, radius_m, mcp_, pip, kProximalRadiusM),
                              CapsuleClearance(centre_xz, radius_m, pip, dip, kMiddleRadiusM));
  if (!links_only) {
    // The holder and its rounded tip as one capsule of the pad's depth about the phalanx's axis.
    const Eigen::Vector2d tip =
        dip + (holder_length_m_ + kTipCapLengthM) * IndexDirection(DistalAngle(mcp_rad));
    clearance = std::min(clearance, CapsuleClearance(centre_xz, radius_m, dip, tip, pad_depth_m_));
  }
  return clearance;
}

double ProstheticKinematics::ThumbClearanceM(double flexion_rad, const Eigen::Vector2d& centre_xz,
                                             double radius_m) const {
  const Eigen::Vector2d ip = ThumbIp(flexion_rad);
  const Eigen::Vector2d tip = ThumbTipCentre(flexion_rad);
  return std::min({(centre_xz - thumb_base_).norm() - radius_m - kThumbProximalRadiusM,
                   CapsuleClearance(centre_xz, radius_m, thumb_base_, ip, kThumbProximalRadiusM),
                   CapsuleClearance(centre_xz, radius_m, ip, tip, thumb_.tip_radius_m)});
}

WrapPose ProstheticKinematics::Wrap(double radius_m, double palm_gap_m, double clearance_m) const {
  const auto fail = [radius_m](const std::string& why) {
    std::ostringstream message;
    message << "a wrap of a " << 2e3 * radius_m << " mm cylinder: " << why;
    throw std::invalid_argument(message.str());
  };
  // Where the cylinder sits when the pad touches it `along` from the pad's centre (towards the tip
  // positive) at MCP q: on the pad's normal there.
  const auto centre_for = [this, radius_m](double q, double along) {
    const DigitContact pad = IndexPadAt(q, along);
    return Eigen::Vector2d(pad.point_xz + radius_m * IndexPalmar(DistalAngle(q)));
  };
  const auto palm_gap = [&](double q, double along) {
    return -kPalmDepthM - (centre_for(q, along).y() + radius_m);
  };
  // From the square pinch to full flexion the pad curls under the palm and the gap closes.
  const double mcp_square = SquarePadMcpRad();
  if (palm_gap(kMcpMaxRad, 0.0) > palm_gap_m) fail("too small: the pad cannot press it against the palm");
  if (palm_gap(mcp_square, 0.0) < palm_gap_m) fail("too large: it reaches the palm before the pad curls under it");
  // Where along the pad it touches: as near the pad's centre as lets the middle phalanx meet the
  // cylinder too (within kWrapLinkContactM), at most at the pad's first mesa row, so that finger,
  // pad and palm close round it together as a hand's wrap does.
  // The pose with the pad touching `along` from its centre; nullopt when no MCP in the range puts the
  // cylinder the gap from the palm there.
  const auto pose_at = [&](double along) -> std::optional<WrapPose> {
    if (palm_gap(kMcpMaxRad, along) > palm_gap_m || palm_gap(mcp_square, along) < palm_gap_m) return std::nullopt;
    WrapPose at;
    at.index_contact_rad = Bisect([&](double q) { return palm_gap(q, along); }, palm_gap_m, mcp_square,
                                  kMcpMaxRad, -1.0);
    at.centre_xz = centre_for(at.index_contact_rad, along);
    at.pad_contact_along_m = along;
    at.index_link_clearance_m = IndexClearanceM(at.index_contact_rad, at.centre_xz, radius_m, true);
    return at;
  };
  // Where the links cannot reach the cylinder (a small one) or only with the pad meeting it from the
  // side (a large one), the pad's centre meets it.
  WrapPose pose = *pose_at(0.0);  // bracketed: checked above
  for (double along = 0.0; along >= -kWrapMaxAlongPadM - 1e-12; along -= kWrapAlongStepM) {
    const std::optional<WrapPose> at = pose_at(along);
    if (!at || IndexPad(at->index_contact_rad).normal_angle_rad < kMinWrapPadNormalRad) break;
    if (at->index_link_clearance_m <= kWrapLinkContactM) {
      pose = *at;
      break;
    }
  }
  if (IndexPad(pose.index_contact_rad).normal_angle_rad < kMinWrapPadNormalRad) {
    fail("too large: the pad would meet it from the side, not press it against the palm");
  }
  if (pose.index_link_clearance_m < kMinLinkClearanceM) {
    fail("too large: the proximal or middle phalanx would meet it before the pad (" +
         std::to_string(pose.index_link_clearance_m * 1e3) + " mm clear)");
  }
  // Open each digit from its contact until every link clears the cylinder by the clearance.
  // The cylinder sits in the palm's hook beside the proximal phalanx's root, which no opening moves
  // away: the index opens until its middle phalanx and holder, which sweep round the cylinder,
  // clear it by the clearance (the proximal phalanx is clear of it from the contact on).
  const auto sweep_clearance = [&](double q) {
    const Eigen::Vector2d tip = Dip(q) + (holder_length_m_ + kTipCapLengthM) * IndexDirection(DistalAngle(q));
    return std::min(CapsuleClearance(pose.centre_xz, radius_m, Pip(q), Dip(q), kMiddleRadiusM),
                    CapsuleClearance(pose.centre_xz, radius_m, Dip(q), tip, pad_depth_m_));
  };
  pose.index_preshape_rad = FirstRoot([&](double q) { return clearance_m - sweep_clearance(q); },
                                      pose.index_contact_rad, kMcpMinRad, kScanStepRad);
  if (std::isnan(pose.index_preshape_rad)) fail("the index cannot open clear of it");
  const auto thumb_gap = [&](double q) { return ThumbClearanceM(q, pose.centre_xz, radius_m); };
  if (thumb_gap(kThumbMinRad) < clearance_m) fail("the thumb cannot open clear of it");
  pose.thumb_contact_rad = FirstRoot(thumb_gap, kThumbMinRad, kThumbMaxRad, kScanStepRad);
  if (std::isnan(pose.thumb_contact_rad)) fail("out of the thumb's reach");
  pose.thumb_preshape_rad = FirstRoot([&](double q) { return clearance_m - thumb_gap(q); },
                                      pose.thumb_contact_rad, kThumbMinRad, kScanStepRad);
  // Lever arms: the pad's travel along its normal per radian; the thumb's point nearest the axis
  // turns about the thumb's base, pushing towards the axis with the arm of its perpendicular.
  constexpr double kStep = 1e-6;
  const double q = pose.index_contact_rad;
  const double along = pose.pad_contact_along_m;
  pose.pad_lever_arm_m = (IndexPadAt(q + kStep, along).point_xz - IndexPadAt(q - kStep, along).point_xz)
                             .dot(IndexPalmar(DistalAngle(q))) /
                         (2.0 * kStep);
  const double t = pose.thumb_contact_rad;
  const Eigen::Vector2d ip = ThumbIp(t);
  const Eigen::Vector2d on_proximal = ClosestOnSegment(pose.centre_xz, thumb_base_, ip);
  const Eigen::Vector2d on_distal = ClosestOnSegment(pose.centre_xz, ip, ThumbTipCentre(t));
  const Eigen::Vector2d nearest = (pose.centre_xz - on_proximal).norm() - kThumbProximalRadiusM <
                                          (pose.centre_xz - on_distal).norm() - thumb_.tip_radius_m
                                      ? on_proximal
                                      : on_distal;
  const Eigen::Vector2d towards = (pose.centre_xz - nearest).normalized();
  const Eigen::Vector2d arm = nearest - thumb_base_;
  pose.thumb_lever_arm_m = std::abs(arm.x() * towards.y() - arm.y() * towards.x());
  return pose;
}

}  // namespace graspbed::sim
