#pragma once
/// What softbake's HTML reports share (compare's, cli/html_report.hpp, and run's,
/// bake/bake_report.hpp): the page around them, its base style, and the script that marks every
/// image that did not load. Self-contained: style and script inline, nothing fetched, so a report
/// opens from a file anywhere its folder is copied.

#include <string>
#include <string_view>

namespace softbake {

/// "<!DOCTYPE html>…<body>\n": the head with `title` (escaped) and the base style followed by
/// `style`, which adds the report's own rules.
std::string reportPageStart(std::string_view title, std::string_view style);

/// "<script>`script` and the image check</script></body></html>\n". The page needs an element
/// `<p id="broken" hidden></p>`, the banner the check fills when an image did not load.
std::string reportPageEnd(std::string_view script);

/// One row of the summary table (`<table class="summary">`): `label` and `text`, both escaped.
std::string summaryRow(std::string_view label, std::string_view text);

}  // namespace softbake
