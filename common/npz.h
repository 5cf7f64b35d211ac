#pragma once
/// NumPy files without NumPy: .npy arrays (format 1.0, little-endian) and .npz archives of them (an
/// uncompressed zip, as numpy.savez writes), so a Python user opens a dataset in one line:
/// `numpy.load("ticks.npz")`. The zip's CRC-32 is zlib's. Written through a temporary name and
/// renamed, so a half-written archive never sits under its final name.

#include <cstdint>
#include <string>
#include <vector>

namespace graspbed::common {

/// One array of an archive: its name (without .npy), NumPy dtype descriptor ("<f4", "<f8", "<i4",
/// "|u1", ...), shape (row-major, C order) and raw little-endian bytes.
struct NpyArray {
  std::string name;
  std::string dtype;
  std::vector<size_t> shape;
  std::vector<uint8_t> bytes;
};

/// An NpyArray of `values` with dtype `dtype` and `shape` (the product of shape must be values.size()).
/// Supported T: float ("<f4"), double ("<f8"), int32_t ("<i4"), int64_t ("<i8"), uint8_t ("|u1").
/// @throws std::invalid_argument when the sizes disagree
template <typename T>
NpyArray MakeNpyArray(const std::string& name, const std::vector<T>& values, std::vector<size_t> shape);

/// The .npy file content (header + data) of `array`.
std::string NpyBytes(const NpyArray& array);

/// Writes `arrays` as an uncompressed .npz at `path` (a temporary file in the same directory, then
/// rename). @throws std::runtime_error naming the path when it cannot be written, or when an array
/// or the archive exceeds the zip's 4 GiB (no zip64).
void WriteNpz(const std::string& path, const std::vector<NpyArray>& arrays);

/// A 1-D or 2-D .npy array of floats read back as doubles (dtype "<f4" or "<f8", C order).
struct NpyMatrix {
  size_t rows = 0;
  size_t columns = 1;        ///< 1 for a 1-D array
  std::vector<double> data;  ///< rows * columns values, row-major
};

/// Reads a .npy file. @throws std::invalid_argument naming the file for anything else.
NpyMatrix ReadNpyMatrix(const std::string& path);

}  // namespace graspbed::common
