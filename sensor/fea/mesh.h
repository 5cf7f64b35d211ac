#pragma once
/// Structured meshes of 9-node quadrilaterals over unions of axis-aligned rectangles.
/// Units throughout sensor/fea: millimetres, newtons, megapascals (N/mm^2).

#include <Eigen/Core>

#include <array>
#include <vector>

namespace graspbed::fea {

/// Axis-aligned rectangle in the model plane [mm]; x along the beam, y up.
struct Rect {
  double x_min = 0.0;
  double x_max = 0.0;
  double y_min = 0.0;
  double y_max = 0.0;
};

/// A mesh of 9-node Lagrange quadrilaterals laid on a tensor grid of element boundary lines.
/// Local node order inside an element is tensor order: local = 3 * b + a, where a = 0, 1, 2 runs
/// along xi (x) and b = 0, 1, 2 along eta (y); so 0 is the bottom-left corner, 4 the centre node
/// and 8 the top-right corner. Elements need not be rectangles (tests build distorted ones), but
/// MeshRectangles only makes rectangles.
struct Mesh {
  std::vector<Eigen::Vector2d> nodes;        ///< node positions [mm]
  std::vector<std::array<int, 9>> elements;  ///< node indices, tensor order (see above)

  // Grid bookkeeping, filled by MeshRectangles (empty for hand-built meshes).
  std::vector<double> x_lines;    ///< element boundaries along x, ascending [mm]
  std::vector<double> y_lines;    ///< element boundaries along y, ascending [mm]
  std::vector<int> cell_element;  ///< element of grid cell (i, j) at j * CellsX() + i, or -1 (void)

  /// Number of grid cells along x.
  int CellsX() const { return static_cast<int>(x_lines.size()) - 1; }
  /// Number of grid cells along y.
  int CellsY() const { return static_cast<int>(y_lines.size()) - 1; }
  /// Element occupying grid cell (i, j), or -1 when the cell is void or outside the grid.
  int CellElement(int i, int j) const;
  /// Number of degrees of freedom (two per node: u_x, u_y).
  int DofCount() const { return 2 * static_cast<int>(nodes.size()); }
};

/// Meshes the union of `rects` with elements no larger than `element_size_mm` in either direction.
/// Every rectangle edge and every value in `extra_x_lines`/`extra_y_lines` becomes a grid line, so
/// element edges fall exactly on geometry and sampling boundaries. Intervals are split evenly.
/// Throws std::invalid_argument for an empty or degenerate rectangle or a non-positive size.
Mesh MeshRectangles(const std::vector<Rect>& rects, double element_size_mm,
                    const std::vector<double>& extra_x_lines = {},
                    const std::vector<double>& extra_y_lines = {});

}  // namespace graspbed::fea
