#include "output/finite_values.hpp"

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

void refuseNonFinite(const std::filesystem::path& file, std::string_view what,
                     std::initializer_list<double> components) {
  std::string values;
  for (double x : components) values += cat(values.empty() ? "" : ", ", x);
  throw Error(cat(file.string(), ": not written: ", what, " is not finite (", values, ")"));
}

}  // namespace softbake
