#include "importers/file_vertices.hpp"

#include <assimp/fast_atof.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include <Eigen/Geometry>

#include "core/mesh/weld.hpp"

namespace softbake {

namespace {

bool isLineEnd(char c) {
  return c == '\r' || c == '\n' || c == '\0' || c == '\f';
}

bool isSpace(char c) {
  return c == ' ' || c == '\t';
}

// assimp's test for a number in a `v` statement: it counts these to tell xyz from xyzw and xyzrgb.
bool countsAsNumber(std::string_view token) {
  const char c = token.front();
  if ((c >= '0' && c <= '9') || c == '-' || c == '+') return true;
  if (token.size() < 3) return false;
  std::string head(token.substr(0, 3));
  for (char& h : head) h = char(std::tolower(static_cast<unsigned char>(h)));
  return head == "nan" || head == "inf";
}

// The next line as assimp's stream buffer hands it to the OBJ parser: a '\' before the line end
// joins the next line.
std::string nextLine(std::string_view text, std::size_t& at) {
  std::string line;
  while (at < text.size()) {
    const char c = text[at];
    if (c == '\\' && at + 1 < text.size() && isLineEnd(text[at + 1])) {
      const std::size_t newline = text.find('\n', at);
      at = newline == std::string_view::npos ? text.size() : newline + 1;
      continue;
    }
    if (isLineEnd(c)) break;
    line += c;
    ++at;
  }
  ++at;
  return line;
}

// What assimp's parser throws here; its own exception's constructor is not exported.
struct NotANumber : std::runtime_error {
  template <class... Parts>
  explicit NotANumber(Parts&&...) : std::runtime_error("not a number") {}
};

float readNumber(const std::string& token) {
  return Assimp::fast_atof<NotANumber>(token.c_str());
}

Vec3f vertexOf(const std::string& line) {
  constexpr float kSkipped = std::numeric_limits<float>::quiet_NaN();
  std::vector<std::string> tokens;
  for (std::size_t i = 1; i < line.size();) {
    while (i < line.size() && isSpace(line[i])) ++i;
    const std::size_t begin = i;
    while (i < line.size() && !isSpace(line[i])) ++i;
    if (i > begin) tokens.emplace_back(line.substr(begin, i - begin));
  }
  const auto numbers = std::count_if(tokens.begin(), tokens.end(), countsAsNumber);
  if (numbers != 3 && numbers != 4 && numbers != 6) return Vec3f::Constant(kSkipped);
  try {
    // assimp's own parser, for the very same floats.
    Vec3f p(readNumber(tokens[0]), readNumber(tokens[1]), readNumber(tokens[2]));
    if (numbers == 4) {
      const float w = readNumber(tokens[3]);
      if (w == 0) return Vec3f::Constant(kSkipped);
      p = Vec3f(p.x() / w, p.y() / w, p.z() / w);
    }
    return p;
  } catch (const std::exception&) {
    return Vec3f::Constant(kSkipped);
  }
}

struct Cell {
  std::int64_t x, y, z;
  bool operator==(const Cell&) const = default;
};

struct CellHash {
  std::size_t operator()(const Cell& c) const {
    return std::size_t(c.x) * 73856093u ^ std::size_t(c.y) * 19349663u ^
           std::size_t(c.z) * 83492791u;
  }
};

}  // namespace

std::vector<Vec3f> objVertexPositions(std::string_view text) {
  std::vector<Vec3f> positions;
  for (std::size_t at = 0; at < text.size();) {
    const std::string line = nextLine(text, at);
    if (line.size() > 1 && line[0] == 'v' && isSpace(line[1])) positions.push_back(vertexOf(line));
  }
  return positions;
}

std::vector<FileVertexPlace> placeByPosition(std::span<const Vec3f> positions,
                                             std::span<const ImportedVertices> meshes) {
  struct Candidate {
    Vec3f position;
    FileVertexPlace place;
  };
  std::vector<Candidate> candidates;
  Eigen::AlignedBox3f bounds;
  std::vector<char> used;
  for (const ImportedVertices& mesh : meshes) {
    used.assign(mesh.positions.size(), 0);
    for (const Triangle& t : mesh.triangles)
      for (Index v : t)
        if (v < used.size()) used[v] = 1;
    for (Index v = 0; v < used.size(); ++v)
      if (used[v]) {
        candidates.push_back({mesh.positions[v], {mesh.mesh, v}});
        bounds.extend(mesh.positions[v]);
      }
  }
  const double diagonal = bounds.isEmpty() ? 0.0 : double(bounds.diagonal().norm());
  const double tolerance = std::max(diagonal * double(kWeldTolerance), 1e-30);
  // As in the weld: clamped, so a far-out position shares a cell instead of overflowing.
  auto cellIndex = [&](float coordinate) {
    return std::int64_t(std::clamp(std::floor(double(coordinate) / tolerance), -0x1p62, 0x1p62));
  };
  auto cellOf = [&](const Vec3f& p) {
    return Cell{cellIndex(p.x()), cellIndex(p.y()), cellIndex(p.z())};
  };
  std::unordered_map<Cell, std::vector<std::size_t>, CellHash> cells;
  for (std::size_t c = 0; c < candidates.size(); ++c)
    cells[cellOf(candidates[c].position)].push_back(c);

  std::vector<FileVertexPlace> places(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3f& p = positions[i];
    if (!p.allFinite()) continue;
    const Cell home = cellOf(p);
    double best = tolerance * tolerance;
    std::size_t found = candidates.size();
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = cells.find({home.x + dx, home.y + dy, home.z + dz});
          if (it == cells.end()) continue;
          for (std::size_t c : it->second) {
            const double distance =
                (candidates[c].position.cast<double>() - p.cast<double>()).squaredNorm();
            if (distance < best || (distance == best && c < found)) {
              best = distance;
              found = c;
            }
          }
        }
    if (found < candidates.size()) places[i] = candidates[found].place;
  }
  return places;
}

}  // namespace softbake
