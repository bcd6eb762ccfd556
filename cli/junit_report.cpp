#include "cli/junit_report.hpp"

#include "bake/markup.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

namespace softbake {

std::string junitXml(const Comparison& comparison) {
  const std::size_t failures = comparison.count(Verdict::Fail);
  const std::string suite =
      escapeMarkup(cat("softbake compare ", comparison.reference, " ", comparison.candidate));
  // The class name groups the cases in CI's view: by what was compared.
  const std::string className = escapeMarkup(cat("softbake.compare.", comparison.kind));
  std::string xml = cat("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites name=\"", suite,
                        "\" tests=\"", comparison.items.size(), "\" failures=\"", failures,
                        "\" errors=\"0\">\n  <testsuite name=\"", suite, "\" tests=\"",
                        comparison.items.size(), "\" failures=\"", failures,
                        "\" errors=\"0\" skipped=\"0\">\n    <properties>\n"
                        "      <property name=\"thresholds\" value=\"",
                        escapeMarkup(comparison.thresholds), "\"/>\n    </properties>\n");
  for (const ComparedItem& item : comparison.items) {
    std::string text = item.summary;
    for (const std::string& line : item.details) text += "\n" + line;
    xml += cat("    <testcase classname=\"", className, "\" name=\"", escapeMarkup(item.name),
               "\">\n");
    if (item.verdict == Verdict::Fail)
      xml += cat("      <failure message=\"", escapeMarkup(item.summary), "\" type=\"differs\">",
                 escapeMarkup(text), "</failure>\n");
    xml += cat("      <system-out>", verdictName(item.verdict), ": ", escapeMarkup(text),
               "</system-out>\n    </testcase>\n");
  }
  xml += "  </testsuite>\n</testsuites>\n";
  return xml;
}

void writeJunit(const std::filesystem::path& path, const Comparison& comparison) {
  if (path.has_parent_path()) makeDirectories(path.parent_path());
  writeFileAtomically(path, junitXml(comparison));
}

}  // namespace softbake
