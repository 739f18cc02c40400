#pragma once
// The live page's files (host_tools/decode/web: index.html, app.js, style.css) and its plotting
// library (Chart.js from Debian's libjs-chart.js), compiled into the program by web/embed.cmake,
// served by the HttpServer as "/", "/app.js", "/style.css" and "/chart.js".
#include <span>

#include "http_server.hpp"

namespace gyrochar::web {

std::span<const Asset> page_assets();

}  // namespace gyrochar::web
