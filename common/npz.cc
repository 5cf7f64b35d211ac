#include "common/npz.h"

#include <zlib.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>

namespace graspbed::common {
namespace {

constexpr uint64_t kZipLimit = std::numeric_limits<uint32_t>::max();

template <typename T>
struct DtypeOf;
template <>
struct DtypeOf<float> {
  static constexpr const char* kName = "<f4";
};
template <>
struct DtypeOf<double> {
  static constexpr const char* kName = "<f8";
};
template <>
struct DtypeOf<int32_t> {
  static constexpr const char* kName = "<i4";
};
template <>
struct DtypeOf<int64_t> {
  static constexpr const char* kName = "<i8";
};
template <>
struct DtypeOf<uint8_t> {
  static constexpr const char* kName = "|u1";
};

std::string NpyHeader(const NpyArray& array) {
  std::string shape = "(";
  for (size_t i = 0; i < array.shape.size(); ++i) shape += std::to_string(array.shape[i]) + ", ";
  if (array.shape.size() > 1) shape.resize(shape.size() - 2);
  shape += ")";
  std::string dict = "{'descr': '" + array.dtype + "', 'fortran_order': False, 'shape': " + shape + ", }";
  // Magic (6) + version (2) + length (2) + dict, padded with spaces and a newline to a multiple of 64.
  const size_t unpadded = 10 + dict.size() + 1;
  dict += std::string((64 - unpadded % 64) % 64, ' ') + "\n";
  std::string header("\x93NUMPY\x01\x00", 8);
  header += static_cast<char>(dict.size() & 0xff);
  header += static_cast<char>((dict.size() >> 8) & 0xff);
  return header + dict;
}

void Put16(std::string& out, uint32_t value) {
  out += static_cast<char>(value & 0xff);
  out += static_cast<char>((value >> 8) & 0xff);
}
void Put32(std::string& out, uint32_t value) {
  Put16(out, value & 0xffff);
  Put16(out, value >> 16);
}

// A zip header: local (signature 0x04034b50) or central (0x02014b50) with `offset` of the local one.
std::string ZipHeader(bool central, const std::string& name, uint32_t crc, uint32_t size, uint32_t offset) {
  std::string out;
  Put32(out, central ? 0x02014b50u : 0x04034b50u);
  if (central) Put16(out, 20);  // version made by
  Put16(out, 20);               // version needed
  Put16(out, 0);                // flags
  Put16(out, 0);                // method: stored
  Put16(out, 0);                // time
  Put16(out, 0x21);             // date: 1980-01-01, fixed so the archive depends on its content only
  Put32(out, crc);
  Put32(out, size);
  Put32(out, size);
  Put16(out, static_cast<uint32_t>(name.size()));
  Put16(out, 0);  // extra
  if (central) {
    Put16(out, 0);  // comment
    Put16(out, 0);  // disk
    Put16(out, 0);  // internal attributes
    Put32(out, 0);  // external attributes
    Put32(out, offset);
  }
  return out + name;
}

std::string TempPathFor(const std::string& path) { return path + ".tmp"; }

}  // namespace

template <typename T>
NpyArray MakeNpyArray(const std::string& name, const std::vector<T>& values, std::vector<size_t> shape) {
  size_t count = 1;
  for (size_t extent : shape) count *= extent;
  if (count != values.size()) {
    throw std::invalid_argument("npy array " + name + ": shape holds " + std::to_string(count) + " values, given " +
                                std::to_string(values.size()));
  }
  NpyArray array{name, DtypeOf<T>::kName, std::move(shape), {}};
  array.bytes.resize(values.size() * sizeof(T));
  if (!values.empty()) std::memcpy(array.bytes.data(), values.data(), array.bytes.size());  // little-endian host
  return array;
}

template NpyArray MakeNpyArray<float>(const std::string&, const std::vector<float>&, std::vector<size_t>);
template NpyArray MakeNpyArray<double>(const std::string&, const std::vector<double>&, std::vector<size_t>);
template NpyArray MakeNpyArray<int32_t>(const std::string&, const std::vector<int32_t>&, std::vector<size_t>);
template NpyArray MakeNpyArray<int64_t>(const std::string&, const std::vector<int64_t>&, std::vector<size_t>);
template NpyArray MakeNpyArray<uint8_t>(const std::string&, const std::vector<uint8_t>&, std::vector<size_t>);

std::string NpyBytes(const NpyArray& array) {
  return NpyHeader(array) + std::string(array.bytes.begin(), array.bytes.end());
}

void WriteNpz(const std::string& path, const std::vector<NpyArray>& arrays) {
  const std::string temp = TempPathFor(path);
  std::ofstream stream(temp, std::ios::binary | std::ios::trunc);
  if (!stream) throw std::runtime_error(path + ": cannot write");
  std::string central;
  uint64_t offset = 0;
  for (const NpyArray& array : arrays) {
    const std::string header = NpyHeader(array);
    const uint64_t size = header.size() + array.bytes.size();
    if (size > kZipLimit || offset > kZipLimit) {
      stream.close();
      std::remove(temp.c_str());
      throw std::runtime_error(path + ": array " + array.name + " would pass the zip's 4 GiB limit; shard the dataset");
    }
    uLong crc = crc32(0L, Z_NULL, 0);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(header.data()), static_cast<uInt>(header.size()));
    // zlib's length is an unsigned int: feed big arrays in pieces.
    for (size_t done = 0; done < array.bytes.size();) {
      const size_t piece = std::min<size_t>(array.bytes.size() - done, 1u << 30);
      crc = crc32(crc, array.bytes.data() + done, static_cast<uInt>(piece));
      done += piece;
    }
    const std::string name = array.name + ".npy";
    const std::string local = ZipHeader(false, name, static_cast<uint32_t>(crc), static_cast<uint32_t>(size), 0);
    central += ZipHeader(true, name, static_cast<uint32_t>(crc), static_cast<uint32_t>(size),
                         static_cast<uint32_t>(offset));
    stream << local << header;
    stream.write(reinterpret_cast<const char*>(array.bytes.data()), static_cast<std::streamsize>(array.bytes.size()));
    offset += local.size() + size;
  }
  std::string end;
  Put32(end, 0x06054b50u);
  Put16(end, 0);
  Put16(end, 0);
  Put16(end, static_cast<uint32_t>(arrays.size()));
  Put16(end, static_cast<uint32_t>(arrays.size()));
  Put32(end, static_cast<uint32_t>(central.size()));
  Put32(end, static_cast<uint32_t>(offset));
  Put16(end, 0);
  stream << central << end;
  stream.flush();
  if (!stream || offset > kZipLimit) {
    stream.close();
    std::remove(temp.c_str());
    throw std::runtime_error(path + ": write error");
  }
  stream.close();
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    throw std::runtime_error(path + ": cannot rename the temporary file into place");
  }
}

NpyMatrix ReadNpyMatrix(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw std::invalid_argument(path + ": cannot read");
  char magic[10];
  stream.read(magic, 10);
  if (!stream || std::memcmp(magic, "\x93NUMPY", 6) != 0 || magic[6] != 1) {
    throw std::invalid_argument(path + ": not a .npy file of format version 1");
  }
  const size_t length = static_cast<uint8_t>(magic[8]) | (static_cast<size_t>(static_cast<uint8_t>(magic[9])) << 8);
  std::string dict(length, ' ');
  stream.read(dict.data(), static_cast<std::streamsize>(length));
  const bool f8 = dict.find("'<f8'") != std::string::npos;
  const bool f4 = dict.find("'<f4'") != std::string::npos;
  if ((!f8 && !f4) || dict.find("'fortran_order': False") == std::string::npos) {
    throw std::invalid_argument(path + ": expected a C-order array of <f4 or <f8, got " + dict);
  }
  const size_t open = dict.find("'shape': (");
  if (open == std::string::npos) throw std::invalid_argument(path + ": no shape in the header");
  NpyMatrix matrix;
  std::vector<size_t> shape;
  const char* cursor = dict.c_str() + open + 10;
  while (*cursor != ')' && *cursor != '\0') {
    char* end = nullptr;
    shape.push_back(std::strtoull(cursor, &end, 10));
    if (end == cursor) break;
    cursor = end;
    while (*cursor == ',' || *cursor == ' ') ++cursor;
  }
  if (shape.empty() || shape.size() > 2) throw std::invalid_argument(path + ": expected a 1-D or 2-D array");
  matrix.rows = shape[0];
  matrix.columns = shape.size() == 2 ? shape[1] : 1;
  const size_t count = matrix.rows * matrix.columns;
  matrix.data.resize(count);
  if (f8) {
    stream.read(reinterpret_cast<char*>(matrix.data.data()), static_cast<std::streamsize>(count * 8));
  } else {
    std::vector<float> values(count);
    stream.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(count * 4));
    for (size_t i = 0; i < count; ++i) matrix.data[i] = values[i];
  }
  if (!stream) throw std::invalid_argument(path + ": shorter than its header says");
  return matrix;
}

}  // namespace graspbed::common
