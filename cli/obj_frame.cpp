#include "cli/obj_frame.hpp"

#include <charconv>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

ObjFrame readObjFrame(const std::filesystem::path& path) {
  std::ifstream file(path);
  if (!file) throw Error(cat(path.string(), ": cannot open the OBJ file"));
  ObjFrame frame;
  const auto current = [&]() -> ObjObject& {
    if (frame.objects.empty())
      frame.objects.push_back({path.stem().string(), frame.positions.size(), 0, {}});
    return frame.objects.back();
  };
  std::string line;
  std::size_t lineNumber = 0;
  std::vector<std::uint32_t> polygon;
  while (std::getline(file, line)) {
    ++lineNumber;
    const auto where = [&] { return cat(path.string(), ":", lineNumber, ": "); };
    if (line.rfind("o ", 0) == 0) {
      std::string name = line.substr(2);
      while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
      frame.objects.push_back({name, frame.positions.size(), 0, {}});
    } else if (line.rfind("v ", 0) == 0) {
      std::istringstream numbers(line.substr(2));
      Vec3f p;
      if (!(numbers >> p.x() >> p.y() >> p.z()))
        throw Error(cat(where(), "a vertex needs three numbers: '", line, "'"));
      current().vertexCount++;
      frame.positions.push_back(p);
    } else if (line.rfind("f ", 0) == 0) {
      ObjObject& object = current();
      polygon.clear();
      std::istringstream corners(line.substr(2));
      std::string corner;
      while (corners >> corner) {
        long index = 0;
        const auto [end, error] =
            std::from_chars(corner.data(), corner.data() + corner.size(), index);
        if (error != std::errc() || index == 0)
          throw Error(cat(where(), "a face corner is not a vertex index: '", corner, "'"));
        // Negative indices count back from the last vertex so far.
        const long absolute = index > 0 ? index - 1 : long(frame.positions.size()) + index;
        if (absolute < long(object.firstVertex) ||
            absolute >= long(object.firstVertex + object.vertexCount))
          throw Error(
              cat(where(), "face index ", index, " is not a vertex of object '", object.name, "'"));
        polygon.push_back(std::uint32_t(std::size_t(absolute) - object.firstVertex));
      }
      if (polygon.size() < 3) throw Error(cat(where(), "a face needs three corners: '", line, "'"));
      for (std::size_t k = 1; k + 1 < polygon.size(); ++k)
        object.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
    }
  }
  return frame;
}

}  // namespace softbake
