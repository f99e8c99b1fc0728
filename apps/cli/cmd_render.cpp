// tendril render SCENE|SESSION -o image.png: grows every plant of a scene (or takes a saved
// session as it is) and renders the result headless (EGL, no window or X server needed) to a PNG.
#include "commands.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/progress.h"
#include "tendril/core/timer.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/image.h"
#include "tendril/render/offscreen.h"
#include "tendril/render/session_render.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"
#include "tendril/session/session_file.h"

#include <fmt/format.h>

#include <charconv>
#include <cstdlib>
#include <optional>

namespace tendril::cli {
namespace {

struct RenderOptions {
  std::string scene;
  std::string output;
  int width = 1280;
  int height = 720;
  int64_t steps = -1;
  int64_t seed = -1;
  std::string eye;
  std::string target;
  double fov = 40.0;
  int samples = 4;
  bool noShadows = false;
  bool air = false;
  bool noStrokes = false;
  CommonOptions common;
};

int runRender(const RenderOptions& o) {
  applyCommonOptions(o.common);
  // llvmpipe (Mesa's software rasteriser) takes its thread count from the environment; keep it
  // within --threads unless the user set it explicitly.
  if (o.common.threads > 0) setenv("LP_NUM_THREADS", std::to_string(o.common.threads).c_str(), 0);

  render::RenderSettings settings;
  settings.width = o.width;
  settings.height = o.height;
  settings.samples = o.samples;
  settings.shadows = !o.noShadows;
  std::optional<Vec3> eye, target;
  if (!o.eye.empty()) eye = parseVec3(o.eye, "--eye");
  if (!o.target.empty()) target = parseVec3(o.target, "--target");
  if (eye && target && (*eye - *target).norm() < 1e-6f)
    throw Error("command line", "--eye", "the eye and the target are the same point");

  // A session file (.tses) is rendered as saved (--steps grows it further); a scene is grown first.
  Timer total;
  std::unique_ptr<session::Session> owned;
  uint32_t steps = 0;
  if (std::filesystem::exists(o.scene) && session::isSessionFile(o.scene)) {
    if (o.seed >= 0) throw Error("command line", "--seed", "a session file keeps its own seed");
    owned = session::loadSession(o.scene).session;
    steps = o.steps >= 0 ? uint32_t(o.steps) : 0;
  } else {
    scene::Scene scene = scene::loadScene(o.scene);
    if (o.steps >= 0) scene.steps = static_cast<int>(o.steps);
    if (o.seed >= 0) scene.seed = static_cast<uint64_t>(o.seed);
    steps = uint32_t(scene.steps);
    owned = std::make_unique<session::Session>(std::move(scene));
  }
  session::Session& session = *owned;
  if (o.air && !session.air())
    throw Error(o.scene, "--air", "the scene has no simulated air (its wind mode is not \"sph\")");
  {
    Progress progress("growing", uint64_t(steps), !o.common.quiet);
    session.run(steps, [&](uint32_t done) {
      progress.update(done, fmt::format("{} segments", session.segmentCount()));
    });
    progress.finish(fmt::format("{} segments", session.segmentCount()));
  }
  double growSeconds = total.seconds();

  render::SessionScene view(session, o.air);
  if (o.noStrokes) view.scene().strokes.clear();
  const float aspect = float(o.width) / float(o.height);
  render::Camera camera = render::frameBounds(render::focusBounds(view.scene()), render::kDefaultViewDirection, aspect,
                                              radians(float(o.fov)));
  if (eye || target) {
    Vec3 offset = camera.eye - camera.target;
    if (target) camera.target = *target;
    camera.eye = eye ? *eye : Vec3(camera.target + offset);
    float distance = (camera.eye - camera.target).norm();
    float extent = render::sceneBounds(view.scene()).size().norm();
    camera.near = std::max(1e-3f, 0.01f * distance);
    camera.far = 100.0f * distance + 2.0f * extent;
    if ((camera.target - camera.eye).normalized().cross(camera.up).norm() < 1e-3f) camera.up = Vec3::UnitZ();
  }

  render::OffscreenRenderer renderer;
  io::Image image = renderer.render(view.scene(), camera, settings);
  const render::FrameStats& stats = renderer.renderer().lastFrame();
  double renderMs = renderer.lastRenderMs();
  io::writeFileAtomic(o.output, io::encodePng(image));

  if (!o.common.quiet) {
    log::info("{}", renderer.context().description());
    log::info("rendered {}×{}: {} branch segments, {} leaves, {} obstacle triangles in {:.1f} ms (instances and "
              "textures {:.1f} ms, upload {:.1f} ms, shaders, drawing and read-back {:.1f} ms)",
              o.width, o.height, stats.branchInstances, stats.leafInstances, stats.obstacleTriangles, renderMs,
              stats.buildMs, stats.uploadMs, renderMs - stats.buildMs - stats.uploadMs);
    log::info("grew {} plant(s) in {} steps (growth {:.2f} s, total {:.2f} s); wrote {}", view.plants().size(),
              session.stepCount(), growSeconds, total.seconds(), o.output);
  }
  return 0;
}

RegisterCommand registerRender("render", "Grow every plant of a scene and render it to a PNG (headless OpenGL)", 20,
                               [](CLI::App& sub) -> std::function<int()> {
  auto o = std::make_shared<RenderOptions>();
  sub.add_option("scene", o->scene, "Scene file (JSON, see docs/scene-format.md) or session file (.tses)")->required();
  sub.add_option("-o,--output", o->output, "PNG file to write (replaced atomically)")->required();
  sub.add_option("--width", o->width, "Image width in pixels")->check(CLI::Range(16, 16384))->capture_default_str();
  sub.add_option("--height", o->height, "Image height in pixels")->check(CLI::Range(16, 16384))->capture_default_str();
  sub.add_option("--steps", o->steps, "Growth steps (overrides the scene's \"steps\"; for a session file: steps to grow on, default 0)")->check(CLI::Range(0, 10000000));
  sub.add_option("--seed", o->seed, "Scene seed (overrides the scene's \"seed\")")->check(CLI::NonNegativeNumber);
  sub.add_option("--eye", o->eye, "Camera position x,y,z (m); default: a 3/4 front view framing the scene");
  sub.add_option("--target", o->target, "Point the camera looks at, x,y,z (m); default: the scene's centre");
  sub.add_option("--fov", o->fov, "Vertical field of view (degrees)")->check(CLI::Range(1.0, 179.0))->capture_default_str();
  sub.add_option("--samples", o->samples, "Multisample anti-aliasing samples (1 = off)")->check(CLI::Range(1, 64))
      ->capture_default_str();
  sub.add_flag("--no-shadows", o->noShadows, "Render without the shadow map");
  sub.add_flag("--no-strokes", o->noStrokes, "Leave out the painted strokes (drawn as dots otherwise)");
  sub.add_flag("--air", o->air, "Also draw the simulated air (wind mode \"sph\") as streaks coloured by speed");
  addCommonOptions(sub, o->common);
  return [o] { return runRender(*o); };
});

}  // namespace
}  // namespace tendril::cli
