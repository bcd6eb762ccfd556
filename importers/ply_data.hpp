#pragma once
/// The data section of a PLY file, walked row by row as its header (ply_guard.hpp) lays it out:
/// ascii as whitespace-separated numbers, binary in either byte order.
///
/// assimp 5.2 fills the rows an ascii file lacks with copies of the last one it read, so a file cut
/// short still comes back with the header's counts. Counting the rows that are really there is
/// the only way to know.

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "importers/ply_guard.hpp"

namespace softbake {

/// One row's values. Integers of every type are exact in a double.
struct PlyRow {
  std::vector<double> scalars;             ///< per property; 0 for a list
  std::vector<std::vector<double>> lists;  ///< per property; empty for a scalar
};

/// How many whole rows of each element `data` (the bytes after the header) holds, in header
/// order; the walk stops at the first row cut short, so every element after it holds 0.
/// Throws softbake::Error starting with `source` and naming the element and row for a value that
/// is not a number, an integer that is not whole, or a negative list length.
std::vector<std::uint64_t> countPlyRows(const PlyHeader& header, std::string_view data,
                                        std::string_view source);

/// Calls `onRow(element, row, values)` for every whole row, in file order, until the data ends.
/// Throws as countPlyRows does.
void readPlyRows(const PlyHeader& header, std::string_view data, std::string_view source,
                 const std::function<void(std::size_t, std::uint64_t, const PlyRow&)>& onRow);

/// The whole file at `path` as bytes. Throws softbake::Error naming it when it cannot be read.
std::string readWholeFile(const std::string& path);

}  // namespace softbake
