#include "output/version.hpp"

namespace softbake {

const char* softbakeVersion() {
  return SOFTBAKE_VERSION;
}

}  // namespace softbake
