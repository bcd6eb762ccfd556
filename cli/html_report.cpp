#include "cli/html_report.hpp"

#include "bake/markup.hpp"
#include "bake/report_page.hpp"
#include "bake/svg_plot.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

namespace softbake {

namespace {

constexpr const char* kStyle = R"(
table.items { border-collapse: collapse; margin-top: 1em; }
table.items th, table.items td { border-top: 1px solid #ccc; padding: 0.4em; text-align: left;
  vertical-align: top; }
td.verdict { font-weight: bold; white-space: nowrap; }
td.numbers { max-width: 32em; font-size: 0.9em; overflow-wrap: anywhere; }
td.numbers div { margin-top: 0.2em; color: #555; }
.pair { position: relative; display: inline-block; line-height: 0; }
.pair img.candidate { position: absolute; left: 0; top: 0;
  clip-path: inset(0 0 0 var(--split, 50%)); }
.controls { margin-top: 0.3em; font-size: 0.85em; }
/* One width for every frame: small test frames scaled up, large ones down. */
img { width: 360px; height: auto; image-rendering: pixelated; }
)";

// The slider moves where the new frame starts over the reference; the toggle shows one whole
// frame, then the other, as flipping between them shows a change best.
constexpr const char* kScript = R"(
for (const row of document.querySelectorAll('tr.item')) {
  const pair = row.querySelector('.pair');
  if (!pair) continue;
  const slider = row.querySelector('input.split');
  const toggle = row.querySelector('button.toggle');
  slider.addEventListener('input', () => pair.style.setProperty('--split', slider.value + '%'));
  toggle.addEventListener('click', () => {
    const showNew = slider.value !== '0';
    slider.value = showNew ? '0' : '100';
    toggle.textContent = showNew ? 'showing new: show reference' : 'showing reference: show new';
    pair.style.setProperty('--split', slider.value + '%');
  });
}
)";

const char* verdictClass(Verdict verdict) {
  return verdict == Verdict::Fail ? "fail" : verdict == Verdict::Warn ? "warn" : "pass";
}

std::string image(const std::string& path, const char* what, const char* className) {
  return cat("<img class=\"", className, "\" src=\"", escapeMarkup(path), "\" alt=\"", what,
             "\" title=\"", what, "\">");
}

std::string row(const ComparedItem& item) {
  std::string html =
      cat("<tr class=\"item ", verdictClass(item.verdict), "\" data-verdict=\"",
          verdictClass(item.verdict), "\" data-name=\"", escapeMarkup(item.name),
          "\">\n<td class=\"name\">", escapeMarkup(item.name), "</td><td class=\"verdict\">",
          verdictName(item.verdict), "</td>\n<td class=\"numbers\">", escapeMarkup(item.summary));
  for (const std::string& line : item.details) html += cat("<div>", escapeMarkup(line), "</div>");
  html += "</td>\n<td class=\"images\">";
  if (!item.referenceImage.empty() && !item.candidateImage.empty())
    html += cat("<div class=\"pair\">", image(item.referenceImage, "reference", "reference"),
                image(item.candidateImage, "new", "candidate"),
                "</div>\n<div class=\"controls\">reference <input class=\"split\" type=\"range\" "
                "min=\"0\" max=\"100\" value=\"50\" aria-label=\"where the new frame starts\"> "
                "new <button class=\"toggle\" type=\"button\">toggle reference / new</button>"
                "</div>");
  else if (!item.referenceImage.empty())
    html += image(item.referenceImage, "reference", "reference");
  else if (!item.candidateImage.empty())
    html += image(item.candidateImage, "new", "candidate");
  html += "</td>\n<td class=\"difference\">";
  if (!item.differenceImage.empty())
    html += image(item.differenceImage, "difference", "difference");
  return html + "</td></tr>\n";
}

}  // namespace

void writeHtmlReport(const std::filesystem::path& folder, const Comparison& comparison) {
  const std::size_t fails = comparison.count(Verdict::Fail),
                    warns = comparison.count(Verdict::Warn);
  const std::string unit = comparison.kind == "images" ? "frames" : "items";
  const std::string headline =
      fails ? cat(fails, " of ", comparison.items.size(), " ", unit, " differ")
            : cat("all ", comparison.items.size(), " ", unit, " within bounds");
  std::string html =
      cat(reportPageStart(cat("softbake compare: ", headline), kStyle),
          "<h1>softbake compare: ", escapeMarkup(comparison.kind), "</h1>\n<p class=\"headline ",
          verdictClass(comparison.worst()), "\" id=\"headline\">", escapeMarkup(headline),
          warns ? cat(", ", warns, " warn") : std::string(),
          "</p>\n<p id=\"broken\" hidden></p>\n<table class=\"summary\">\n",
          summaryRow("reference", comparison.reference), summaryRow("new", comparison.candidate),
          summaryRow("thresholds", comparison.thresholds),
          summaryRow("counts", cat(fails, " differ, ", warns, " warn, ",
                                   comparison.count(Verdict::Pass), " ok")));
  for (const std::string& note : comparison.notes) html += summaryRow("note", note);
  html += "</table>\n";
  if (!comparison.plots.empty()) {
    html += "<section id=\"plots\">\n";
    for (const Plot& plot : comparison.plots) html += svgLineChart(plot);
    html += "</section>\n";
  }
  html +=
      "<table class=\"items\" id=\"items\">\n<thead><tr><th>item</th><th>verdict</th>"
      "<th>numbers</th><th>reference / new</th><th>difference</th></tr></thead>\n<tbody>\n";
  for (const ComparedItem* item : reportOrder(comparison)) html += row(*item);
  html += cat("</tbody>\n</table>\n", reportPageEnd(kScript));
  makeDirectories(folder);
  writeFileAtomically(folder / "index.html", html);
}

}  // namespace softbake
