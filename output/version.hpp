#pragma once
/// The softbake version recorded in every file the exporters write.

namespace softbake {

/// "0.1.0": the CMake project version.
const char* softbakeVersion();

}  // namespace softbake
