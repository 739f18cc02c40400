#pragma once
// The live page's files (host_tools/decode/web: index.html, app.js, style.css), compiled into the
// program by web/embed.cmake, served by the HttpServer as "/", "/app.js" and "/style.css".
#include <span>

#include "http_server.hpp"

namespace gyrochar::web {

std::span<const Asset> page_assets();

}  // namespace gyrochar::web
