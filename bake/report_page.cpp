#include "bake/report_page.hpp"

#include "bake/markup.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

constexpr const char* kBaseStyle = R"(
body { font-family: sans-serif; margin: 1.5em; color: #222; }
h1 { font-size: 1.4em; margin-bottom: 0.2em; }
.headline { font-size: 1.2em; font-weight: bold; padding: 0.4em 0.8em; display: inline-block; }
.headline.fail, tr.fail td.verdict { background: #f8d0d0; color: #8a0000; }
.headline.warn, tr.warn td.verdict { background: #fbecc0; color: #6b4e00; }
.headline.pass, tr.pass td.verdict { background: #d4f0d4; color: #185c18; }
table.summary td { padding: 0.1em 0.8em 0.1em 0; vertical-align: top; }
#broken { background: #f8d0d0; padding: 0.5em; }
)";

// Every image marks whether it loaded, and a banner says so when some did not (a report copied
// without its images). An image whose source a script changes later is marked by that script.
constexpr const char* kImageCheck = R"(
const banner = document.getElementById('broken');
function mark(image, loaded) {
  image.dataset.state = loaded ? 'loaded' : 'broken';
  const broken = document.querySelectorAll('img[data-state=broken]').length;
  banner.hidden = broken === 0;
  banner.textContent = broken + ' image(s) did not load: keep the report folder whole.';
}
for (const image of document.images) {
  if (image.complete) mark(image, image.naturalWidth > 0);
  else {
    image.addEventListener('load', () => mark(image, true));
    image.addEventListener('error', () => mark(image, false));
  }
}
)";

}  // namespace

std::string reportPageStart(std::string_view title, std::string_view style) {
  return cat("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>",
             escapeMarkup(title), "</title>\n<style>", kBaseStyle, style,
             "</style>\n</head>\n<body>\n");
}

std::string reportPageEnd(std::string_view script) {
  return cat("<script>", kImageCheck, script, "</script>\n</body>\n</html>\n");
}

std::string summaryRow(std::string_view label, std::string_view text) {
  return cat("<tr><td>", escapeMarkup(label), "</td><td>", escapeMarkup(text), "</td></tr>\n");
}

}  // namespace softbake
