// The report's HTML: the page of assets/report.html (styles in assets/report.css, the drawing
// script in assets/report.js, embedded_assets.h) around the run's data as JSON. Plots are small
// hand-written SVG; the 3D view is three.js. The page marks what it drew in data attributes
// (data-n on every plot, data-drawn-points and data-lit-pixels on the 3D view, data-ready and
// data-errors on the body) so that a test in a headless browser can check it.
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>

#include "flowfusion/report/embedded_assets.h"
#include "flowfusion/report/report_parts.h"

namespace ff::report {
namespace {

// JSON inside <script>: "</" would end the element early.
std::string scriptSafe(std::string json) {
  for (size_t p = json.find("</"); p != std::string::npos; p = json.find("</", p + 3)) json.replace(p, 2, "<\\/");
  return json;
}

std::string htmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// The template with each {{name}} replaced by fields[name]; only the template is scanned, so a
// field's text (the run's data) may hold anything. An unknown or unclosed field is a programming
// mistake in assets/report.html (std::logic_error).
std::string fillTemplate(std::string_view page, const std::map<std::string_view, std::string_view>& fields) {
  std::string out;
  size_t from = 0;
  for (size_t open = page.find("{{"); open != std::string_view::npos; open = page.find("{{", from)) {
    const size_t close = page.find("}}", open);
    if (close == std::string_view::npos) throw std::logic_error("report.html: unclosed {{ field");
    const auto field = fields.find(page.substr(open + 2, close - open - 2));
    if (field == fields.end())
      throw std::logic_error("report.html: unknown field " + std::string(page.substr(open, close + 2 - open)));
    out.append(page.substr(from, open - from)).append(field->second);
    from = close + 2;
  }
  return out.append(page.substr(from));
}

}  // namespace

std::string renderPage(const nlohmann::json& data) {
  const std::string title = htmlEscape(data.value("sequence", std::string("run")));
  const std::string json = scriptSafe(data.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  // The embedded libraries go in verbatim from Debian's libjs-three (between the page's markers).
  return fillTemplate(reportPageHtml(), {{"title", title},
                                         {"style", reportCss()},
                                         {"three_js", threeJs()},
                                         {"orbit_controls_js", orbitControlsJs()},
                                         {"data", json},
                                         {"script", reportJs()}});
}

}  // namespace ff::report
