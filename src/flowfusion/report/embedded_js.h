#pragma once
// JavaScript libraries compiled into the executable (from Debian's libjs-three at build time, see
// embedded_js.cmake): the report embeds them so that it opens offline anywhere.
#include <string_view>

namespace ff::report {

std::string_view threeJs();          // three.min.js (r111): WebGL scene, points, lines
std::string_view orbitControlsJs();  // examples/js/controls/OrbitControls.js: rotate, pan, zoom
}  // namespace ff::report
