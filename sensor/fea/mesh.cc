#include "sensor/fea/mesh.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace graspbed::fea {
namespace {

constexpr double kLineMergeTolMm = 1e-9;  // grid lines closer than this are one line

// Sorted breakpoints with near-duplicates merged.
std::vector<double> UniqueSorted(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  std::vector<double> unique;
  for (double value : values) {
    if (unique.empty() || value - unique.back() > kLineMergeTolMm) unique.push_back(value);
  }
  return unique;
}

// Splits each interval between breakpoints into equal parts no longer than `size`.
std::vector<double> Subdivide(const std::vector<double>& breaks, double size) {
  std::vector<double> lines;
  for (size_t k = 0; k + 1 < breaks.size(); ++k) {
    const double length = breaks[k + 1] - breaks[k];
    // The small slack keeps 0.2 / 0.05 at 4 parts despite rounding.
    const int parts = std::max(1, static_cast<int>(std::ceil(length / size - 1e-9)));
    for (int p = 0; p < parts; ++p) lines.push_back(breaks[k] + length * p / parts);
  }
  lines.push_back(breaks.back());
  return lines;
}

}  // namespace

int Mesh::CellElement(int i, int j) const {
  if (i < 0 || j < 0 || i >= CellsX() || j >= CellsY()) return -1;
  return cell_element[static_cast<size_t>(j) * CellsX() + i];
}

Mesh MeshRectangles(const std::vector<Rect>& rects, double element_size_mm,
                    const std::vector<double>& extra_x_lines, const std::vector<double>& extra_y_lines) {
  if (rects.empty()) throw std::invalid_argument("MeshRectangles: no rectangles to mesh");
  if (!(element_size_mm > 0.0)) {
    throw std::invalid_argument("MeshRectangles: element size " + std::to_string(element_size_mm) +
                                " mm: must be > 0");
  }
  std::vector<double> x_breaks;
  std::vector<double> y_breaks;
  double x_lo = rects.front().x_min, x_hi = rects.front().x_max;
  double y_lo = rects.front().y_min, y_hi = rects.front().y_max;
  for (const Rect& rect : rects) {
    if (!(rect.x_max > rect.x_min) || !(rect.y_max > rect.y_min)) {
      throw std::invalid_argument("MeshRectangles: degenerate rectangle [" + std::to_string(rect.x_min) +
                                  ", " + std::to_string(rect.x_max) + "] x [" + std::to_string(rect.y_min) +
                                  ", " + std::to_string(rect.y_max) + "] mm");
    }
    x_breaks.insert(x_breaks.end(), {rect.x_min, rect.x_max});
    y_breaks.insert(y_breaks.end(), {rect.y_min, rect.y_max});
    x_lo = std::min(x_lo, rect.x_min);
    x_hi = std::max(x_hi, rect.x_max);
    y_lo = std::min(y_lo, rect.y_min);
    y_hi = std::max(y_hi, rect.y_max);
  }
  // Extra lines only matter inside the meshed extent.
  for (double x : extra_x_lines) {
    if (x > x_lo && x < x_hi) x_breaks.push_back(x);
  }
  for (double y : extra_y_lines) {
    if (y > y_lo && y < y_hi) y_breaks.push_back(y);
  }

  Mesh mesh;
  mesh.x_lines = Subdivide(UniqueSorted(x_breaks), element_size_mm);
  mesh.y_lines = Subdivide(UniqueSorted(y_breaks), element_size_mm);
  const int cells_x = mesh.CellsX();
  const int cells_y = mesh.CellsY();
  mesh.cell_element.assign(static_cast<size_t>(cells_x) * cells_y, -1);

  // Node grid at twice the cell resolution (corner, mid-edge and centre nodes).
  const int grid_x = 2 * cells_x + 1;
  const int grid_y = 2 * cells_y + 1;
  std::vector<int> grid_node(static_cast<size_t>(grid_x) * grid_y, -1);
  auto node_at = [&](int gi, int gj) {
    int& id = grid_node[static_cast<size_t>(gj) * grid_x + gi];
    if (id < 0) {
      const int ci = gi / 2, cj = gj / 2;
      const double x = gi % 2 == 0 ? mesh.x_lines[ci] : 0.5 * (mesh.x_lines[ci] + mesh.x_lines[ci + 1]);
      const double y = gj % 2 == 0 ? mesh.y_lines[cj] : 0.5 * (mesh.y_lines[cj] + mesh.y_lines[cj + 1]);
      id = static_cast<int>(mesh.nodes.size());
      mesh.nodes.emplace_back(x, y);
    }
    return id;
  };

  for (int j = 0; j < cells_y; ++j) {
    for (int i = 0; i < cells_x; ++i) {
      const double cx = 0.5 * (mesh.x_lines[i] + mesh.x_lines[i + 1]);
      const double cy = 0.5 * (mesh.y_lines[j] + mesh.y_lines[j + 1]);
      const bool inside = std::any_of(rects.begin(), rects.end(), [&](const Rect& r) {
        return cx > r.x_min && cx < r.x_max && cy > r.y_min && cy < r.y_max;
      });
      if (!inside) continue;
      std::array<int, 9> element{};
      for (int b = 0; b < 3; ++b) {
        for (int a = 0; a < 3; ++a) element[3 * b + a] = node_at(2 * i + a, 2 * j + b);
      }
      mesh.cell_element[static_cast<size_t>(j) * cells_x + i] = static_cast<int>(mesh.elements.size());
      mesh.elements.push_back(element);
    }
  }
  return mesh;
}

}  // namespace graspbed::fea
