#include "exporters/texcoord_table.hpp"

#include <bit>
#include <cstdint>
#include <unordered_map>

namespace softbake {

namespace {

struct UvHash {
  std::size_t operator()(const Vec2f& uv) const {
    // Adding +0 turns -0 into +0, so values that compare equal hash alike.
    const auto u = std::bit_cast<std::uint32_t>(uv.x() + 0.0f);
    const auto v = std::bit_cast<std::uint32_t>(uv.y() + 0.0f);
    return (std::size_t(u) << 32 | v) * 0x9E3779B97F4A7C15ull >> 7;
  }
};

}  // namespace

TexcoordTable texcoordTable(const RenderMesh& render) {
  TexcoordTable table;
  if (render.uvs.empty()) return table;
  std::unordered_map<Vec2f, Index, UvHash> index;
  table.corners.reserve(render.renderTriangles.size());
  for (const Triangle& triangle : render.renderTriangles) {
    Triangle& corners = table.corners.emplace_back();
    for (int corner = 0; corner < 3; ++corner) {
      const Vec2f& uv = render.uvs[triangle[corner]];
      const auto [it, added] = index.try_emplace(uv, Index(table.uvs.size()));
      if (added) table.uvs.push_back(uv);
      corners[corner] = it->second;
    }
  }
  return table;
}

}  // namespace softbake
