#include "experiments/fields/npy.h"

#include <bit>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "util/error.h"
#include "util/io.h"

namespace quijibo::fields {

static_assert(std::endian::native == std::endian::little, "npy I/O assumes a little-endian machine");

namespace {

// The value of `key` in the header dict ("'descr': '<f8', 'fortran_order': False, 'shape': (3, 4), }").
std::string HeaderValue(const std::string& header, const std::string& key, const std::string& path) {
  const std::size_t k = header.find("'" + key + "'");
  if (k == std::string::npos) throw Error(path + ": .npy header has no '" + key + "'");
  std::size_t v = header.find(':', k);
  if (v == std::string::npos) throw Error(path + ": .npy header: no value for '" + key + "'");
  ++v;
  while (v < header.size() && header[v] == ' ') ++v;
  std::size_t end = v;
  if (header[v] == '(') {
    end = header.find(')', v);
    if (end == std::string::npos) throw Error(path + ": .npy header: unterminated shape");
    return header.substr(v, end - v + 1);
  }
  if (header[v] == '\'') {
    end = header.find('\'', v + 1);
    if (end == std::string::npos) throw Error(path + ": .npy header: unterminated string");
    return header.substr(v + 1, end - v - 1);
  }
  while (end < header.size() && header[end] != ',' && header[end] != '}') ++end;
  return header.substr(v, end - v);
}

}  // namespace

NpyArray ReadNpy(const std::string& path) {
  const std::string bytes = ReadFile(path);
  if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0) throw Error(path + ": not a .npy file");
  const int major = static_cast<unsigned char>(bytes[6]);
  std::size_t header_len = 0, start = 0;
  if (major == 1) {
    header_len = std::size_t(static_cast<unsigned char>(bytes[8])) | (std::size_t(static_cast<unsigned char>(bytes[9])) << 8);
    start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) throw Error(path + ": truncated .npy header");
    std::uint32_t len = 0;
    std::memcpy(&len, bytes.data() + 8, 4);
    header_len = len;
    start = 12;
  } else {
    throw Error(path + ": .npy version " + std::to_string(major) + " (expected 1, 2 or 3)");
  }
  if (bytes.size() < start + header_len) throw Error(path + ": truncated .npy header");
  const std::string header = bytes.substr(start, header_len);
  const std::string descr = HeaderValue(header, "descr", path);
  if (descr != "<f8") throw Error(path + ": dtype '" + descr + "' (expected float64, '<f8')");
  if (HeaderValue(header, "fortran_order", path) != "False") throw Error(path + ": Fortran order (expected C order)");
  NpyArray a;
  std::string shape = HeaderValue(header, "shape", path);
  shape = shape.substr(1, shape.size() - 2);
  std::size_t count = 1;
  std::stringstream ss(shape);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.find_first_not_of(' ') == std::string::npos) continue;
    const std::size_t d = std::stoull(item);
    a.shape.push_back(d);
    count *= d;
  }
  const std::size_t data_start = start + header_len;
  if (bytes.size() != data_start + count * 8)
    throw Error(path + ": " + std::to_string(bytes.size() - data_start) + " data bytes for shape (" + shape +
                ") (expected " + std::to_string(count * 8) + ")");
  a.data.resize(count);
  if (count > 0) std::memcpy(a.data.data(), bytes.data() + data_start, count * 8);
  return a;
}

void WriteNpy(const std::string& path, const std::vector<std::size_t>& shape, const std::vector<double>& data) {
  std::string dims;
  std::size_t count = 1;
  for (std::size_t d : shape) dims += std::to_string(d) + ", ", count *= d;
  if (shape.size() > 1) dims.resize(dims.size() - 2);
  if (count != data.size()) throw Error(path + ": shape does not match the data");
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" + dims + "), }";
  // Magic (6) + version (2) + length (2) + header + '\n' padded to a multiple of 64.
  const std::size_t total = (10 + header.size() + 1 + 63) / 64 * 64;
  header.append(total - 10 - header.size() - 1, ' ');
  header += '\n';
  std::string bytes = std::string("\x93NUMPY\x01\x00", 8);
  bytes += char(header.size() & 0xff);
  bytes += char(header.size() >> 8);
  bytes += header;
  const std::size_t at = bytes.size();
  bytes.resize(at + data.size() * 8);
  if (!data.empty()) std::memcpy(bytes.data() + at, data.data(), data.size() * 8);
  WriteFileAtomically(path, bytes);
}

}  // namespace quijibo::fields
