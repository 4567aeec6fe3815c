// NumPy .npy files of float64 (little-endian, C order): the exchange format of `quijibo-fields`
// with the gallery's Python scripts (numpy.load / numpy.save read and write them as they are).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace quijibo::fields {

struct NpyArray {
  std::vector<std::size_t> shape;
  std::vector<double> data;  // C order
};

// Reads a version 1.x/2.x .npy holding '<f8' in C order. Throws quijibo::Error naming the file and
// what was found otherwise (another dtype, Fortran order, a truncated file).
NpyArray ReadNpy(const std::string& path);
// Writes `data` (C order, the product of `shape` values) as a version 1.0 .npy, atomically.
void WriteNpy(const std::string& path, const std::vector<std::size_t>& shape, const std::vector<double>& data);

}  // namespace quijibo::fields
