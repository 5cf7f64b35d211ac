#pragma once
/// The labelled picture of a layout (`graspbed sensor layout --picture`): the holder's palmar half
/// unrolled into a plane, every unit's beam and mesa at scale with its number, beam direction and +Ft
/// sense, the rows and columns named. Built from the Layout alone, so it follows the layout file.
#include "common/plot.h"
#include "sensor/layout.h"

namespace graspbed::sensor {

/// Colour of the mesas of units whose beam runs along the holder axis.
inline constexpr plot::Colour kAxialBeamColour{0.00, 0.45, 0.70};
/// Colour of the mesas of units whose beam runs around the circumference.
inline constexpr plot::Colour kCircumferentialBeamColour{0.84, 0.37, 0.00};

/// The palmar surface of `layout`'s holder unrolled, seen from outside (from the palm): the holder
/// axis x horizontal, distal (the fingertip, +x) to the left; arc length from the palmar midline
/// vertical, +y up; both in millimetres at one scale. Each unit: its beam's outline (beam length x
/// width), its mesa filled in its orientation's colour, its index in layout order, and an arrow
/// from the mesa along the beam in the sense of its +Ft (UnitPose::beam_axis). Rows are named above,
/// columns at the side; notes under the drawing state the holder frame and the colours.
plot::Drawing LayoutDrawing(const Layout& layout);

}  // namespace graspbed::sensor
