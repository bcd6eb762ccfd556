#pragma once
/// What a minimal OBJ reader sees in the OBJ frames softbake writes, for the tests that check
/// them: numbers parsed exactly with from_chars, so a test can compare them bit for bit.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"

namespace softbake::test {

/// What a minimal OBJ reader sees, numbers parsed exactly with from_chars.
struct ParsedObj {
  std::vector<std::string> objects, materials;
  std::vector<Vec3> v;
  std::vector<Vec2f> vt;
  std::vector<Vec3f> vn;
  std::vector<std::array<std::array<long, 3>, 3>> faces;  ///< v/vt/vn per corner, 0 when absent
  std::vector<std::size_t> facesPerObject;
  std::string mtllib;
};

template <class Number>
Number parseNumber(std::string_view text) {
  Number value{};
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  EXPECT_TRUE(error == std::errc() && end == text.data() + text.size()) << text;
  return value;
}

inline ParsedObj parseObj(const std::string& text) {
  ParsedObj obj;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string keyword, a, b, c;
    words >> keyword >> a >> b >> c;
    if (keyword == "o") {
      obj.objects.push_back(a);
      obj.facesPerObject.push_back(0);
    } else if (keyword == "usemtl") {
      obj.materials.push_back(a);
    } else if (keyword == "mtllib") {
      obj.mtllib = a;
    } else if (keyword == "v") {
      obj.v.emplace_back(parseNumber<Scalar>(a), parseNumber<Scalar>(b), parseNumber<Scalar>(c));
    } else if (keyword == "vt") {
      obj.vt.emplace_back(parseNumber<float>(a), parseNumber<float>(b));
    } else if (keyword == "vn") {
      obj.vn.emplace_back(parseNumber<float>(a), parseNumber<float>(b), parseNumber<float>(c));
    } else if (keyword == "f") {
      std::array<std::array<long, 3>, 3> face{};
      const std::string corners[3] = {a, b, c};
      for (int k = 0; k < 3; ++k) {
        std::string_view rest = corners[k];
        for (int part = 0; part < 3; ++part) {
          const std::size_t slash = std::min(rest.find('/'), rest.size());
          if (slash > 0) face[k][part] = parseNumber<long>(rest.substr(0, slash));
          rest.remove_prefix(std::min(slash + 1, rest.size()));
        }
      }
      obj.faces.push_back(face);
      ++obj.facesPerObject.back();
    } else {
      EXPECT_TRUE(keyword.empty() || keyword[0] == '#' || keyword == "s") << line;
    }
  }
  return obj;
}

}  // namespace softbake::test
