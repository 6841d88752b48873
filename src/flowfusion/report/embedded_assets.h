#pragma once
// Files compiled into the executable (embedded_assets.cmake): the report page's own HTML, CSS and
// script (report/assets/) and the JavaScript libraries from Debian's libjs-three at build time.
// The report embeds them so that it opens offline anywhere.
#include <string_view>

namespace ff::report {

std::string_view threeJs();          // three.min.js (r111): WebGL scene, points, lines
std::string_view orbitControlsJs();  // examples/js/controls/OrbitControls.js: rotate, pan, zoom
// assets/report.html: the page around its {{name}} fields (renderPage fills them).
std::string_view reportPageHtml();
std::string_view reportCss();  // assets/report.css
std::string_view reportJs();   // assets/report.js: draws the page from its JSON data

}  // namespace ff::report
