#include "output/frame_naming.hpp"

#include <charconv>

#include "core/text.hpp"

namespace softbake {

std::string FrameNaming::fileName(int frameNumber) const {
  char digits[16];
  char* const end = std::to_chars(digits, digits + sizeof digits, frameNumber).ptr;
  const std::size_t length = std::size_t(end - digits);
  std::string name = scene + "_";
  if (length < std::size_t(padding)) name.append(std::size_t(padding) - length, '0');
  name.append(digits, length);
  return name + extension;
}

std::string FrameNaming::relativePath(int frameNumber) const {
  return folder + "/" + fileName(frameNumber);
}

std::string FrameNaming::pattern() const {
  return cat(folder, "/", scene, "_", std::string(std::size_t(padding), '#'), extension);
}

std::string FrameNaming::printfPattern() const {
  return cat(folder, "/", scene, "_%0", padding, "d", extension);
}

}  // namespace softbake
