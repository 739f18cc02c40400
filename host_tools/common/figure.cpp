#include "figure.hpp"

#include <fmt/format.h>
#include <plplot/plstream.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>

// LeakSanitizer reads this hook in the sanitizer build (unused otherwise): PLplot's cairo driver
// leaves fontconfig's font caches and libltdl's loaded driver for the life of the process, by design
// of those libraries; neither is ours to free.
extern "C" const char* __lsan_default_suppressions() { return "leak:libfontconfig.so\nleak:libltdl.so\n"; }

namespace gyrochar {
namespace {

bool draw(const char* device, const std::string& file, std::size_t panels, const Palette& palette, int width, int height,
          const std::function<void(plstream&, std::size_t)>& draw_panel, std::string& why) {
  // PLplot would end the process on a file it cannot open: check first.
  if (std::FILE* f = std::fopen(file.c_str(), "w")) {
    std::fclose(f);
  } else {
    why = fmt::format("{}: {}", file, std::strerror(errno));
    return false;
  }
  const auto columns = static_cast<PLINT>(std::ceil(std::sqrt(static_cast<double>(panels))));
  const auto rows = static_cast<PLINT>((static_cast<PLINT>(panels) + columns - 1) / columns);
  {
    plstream pls;
    pls.sdev(device);
    pls.sfnam(file.c_str());
    pls.spage(0, 0, width * columns, height * rows, 0, 0);
    std::vector<PLINT> red, green, blue;
    for (const auto& [r, g, b] : palette) {
      red.push_back(r);
      green.push_back(g);
      blue.push_back(b);
    }
    pls.scmap0(red.data(), green.data(), blue.data(), static_cast<PLINT>(palette.size()));
    pls.ssub(columns, rows);
    pls.init();
    for (std::size_t k = 0; k < panels; ++k) draw_panel(pls, k);
  }  // plend1: the file is complete
  return true;
}

}  // namespace

std::string plot_devices_missing() {
  std::array<const char*, 128> menu_storage{}, name_storage{};  // plgDevs fills arrays of the caller's
  const char** menus = menu_storage.data();
  const char** names = name_storage.data();
  int count = static_cast<int>(name_storage.size());
  plgDevs(&menus, &names, &count);
  std::string missing;
  for (const char* wanted : {"svgcairo", "pngcairo"}) {
    if (std::none_of(names, names + count, [&](const char* n) { return std::strcmp(n, wanted) == 0; }))
      missing += std::string(missing.empty() ? "" : ", ") + wanted;
  }
  return missing.empty() ? "" : "PLplot has no " + missing + " device (Debian package plplot-driver-cairo)";
}

void draw_empty_panel(plstream& pls, const std::string& title, const char* message) {
  pls.vpor(0.1, 0.9, 0.1, 0.9);
  pls.wind(0, 1, 0, 1);
  pls.box("bc", 0, 0, "bc", 0, 0);
  pls.ptex(0.5, 0.5, 1, 0, 0.5, message);
  pls.lab("", "", title.c_str());
}

bool write_figure(const std::string& prefix, std::size_t panels, const Palette& palette, int panel_width, int panel_height,
                  const std::function<void(plstream&, std::size_t)>& draw_panel, std::string& why) {
  for (const auto& [device, extension] : {std::pair{"svgcairo", ".svg"}, std::pair{"pngcairo", ".png"}}) {
    const std::string file = prefix + extension, part = file + ".part";
    if (!draw(device, part, panels, palette, panel_width, panel_height, draw_panel, why)) return false;
    if (std::rename(part.c_str(), file.c_str()) != 0) {
      why = fmt::format("{}: {}", file, std::strerror(errno));
      std::remove(part.c_str());
      return false;
    }
  }
  return true;
}

}  // namespace gyrochar
