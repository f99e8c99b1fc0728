// tendril-studio: interactive authoring of growing plants (GLFW window, Dear ImGui panels) and
// its headless mode for scripts and tests. See docs/studio.md.
#include "options.h"
#include "studio.h"

#include "tendril/core/error.h"
#include "tendril/render/impostor_baker.h"

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  using namespace tendril;
  render::installRendererImpostorBaker();  // output.impostor in the studio's export
  studio::StudioOptions options;
  try {
    options = studio::parseOptions(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const Error& e) {
    std::fprintf(stderr, "tendril-studio: %s\n", e.what());
    return 2;
  }
  if (options.help) {
    std::fputs(studio::usage().c_str(), stdout);
    return 0;
  }
  try {
    studio::Studio app(options);
    return app.run();
  } catch (const Error& e) {
    std::fprintf(stderr, "tendril-studio: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tendril-studio: %s\n", e.what());
    return 1;
  }
}
