#include "plant_output.h"

#include "tendril/core/error.h"

#include <fmt/format.h>

namespace tendril::cli {

std::set<std::string> parseFormats(const std::string& list) {
  std::set<std::string> out;
  size_t start = 0;
  while (start <= list.size()) {
    size_t comma = list.find(',', start);
    std::string f = list.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (f != "glb" && f != "obj" && f != "skeleton")
      throw Error("command line", "--format",
                  fmt::format("unknown format \"{}\" (expected glb, obj, skeleton or a comma-separated list of them)", f));
    out.insert(f);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

std::filesystem::path prepareOutputDir(const std::string& dir) {
  std::filesystem::path p(dir);
  std::error_code ec;
  if (std::filesystem::exists(p, ec) && !std::filesystem::is_directory(p, ec))
    throw Error("command line", "-o", fmt::format("{} exists and is not a directory", dir));
  std::filesystem::create_directories(p, ec);
  if (ec) throw Error("command line", "-o", fmt::format("cannot create directory {}: {}", dir, ec.message()));
  return p;
}

void addLodOptions(CLI::App& sub, LodOptions& options) {
  sub.add_option("--lods", options.lods,
                 "Levels of detail per plant, LOD0 included (overrides the scene's output.lods; 1 = none): "
                 "MSFT_lod nodes <plant>_LOD<k> in .glb, <stem>_LOD<k>.obj files")
      ->check(CLI::Range(1, 8));
  sub.add_option("--lod-ratio", options.ratio,
                 "Triangle budget of LODk: LOD0's triangles x ratio^k (overrides the scene's output.lod_ratio and "
                 "lod_triangles; default 0.45)")
      ->check(CLI::Range(0.01, 1.0));
  sub.add_flag("--leaf-atlas", options.leafAtlas,
               "Pack each plant's leaf textures into one atlas, its leaves one material and one mesh part (sets the "
               "scene's output.leaf_atlas)");
  sub.add_flag("--wind-data", options.windData,
               "Engine wind data in the .glb: per vertex the pivot it bends about, its lever, branch level, phase and "
               "period (COLOR_0, _WIND_PIVOT, _WIND_AXIS; docs/engine-wind.md; sets the scene's output.wind_data)");
  sub.add_flag("--impostor", options.impostor,
               "A billboard impostor as each plant's last level of detail: slab quads baked with the renderer "
               "(colour + normal atlas, alpha-tested; docs/export.md; sets the scene's output.impostor)");
  sub.add_flag("--instancing", options.instancing,
               "GPU instancing in the .glb: a graph plant's repeated primitive shapes written once each and drawn "
               "per copy (EXT_mesh_gpu_instancing, required), where that makes the file smaller (sets the scene's "
               "output.instancing)");
  sub.add_flag("--maps", options.maps,
               "Bark normal and roughness maps and leaf normal maps, made with their textures (glTF normalTexture and "
               "metallicRoughnessTexture, .obj norm and map_Pr; sets the scene's output.maps)");
  sub.add_flag("--pivot-painter", options.pivotPainter,
               "Pivot Painter 2 textures beside the .glb, per plant: <stem>-<plant>-pp-pivot.exr (pivot, parent index) "
               "and <stem>-<plant>-pp-xaxis.png (axis, extent), indexed by the .glb's TEXCOORD_1 (docs/export.md; "
               "sets the scene's output.pivot_painter)");
}

void applyLodOptions(const LodOptions& options, scene::OutputSettings& output) {
  if (options.impostor) output.impostor = true;
  if (options.leafAtlas) output.leafAtlas = true;
  if (options.windData) output.windData = true;
  if (options.instancing) output.instancing = true;
  if (options.maps) output.maps = true;
  if (options.pivotPainter) output.pivotPainter = true;
  if (options.lods > 0) {
    output.lods = options.lods;
    output.lodTriangles.clear();
  }
  if (options.ratio > 0.0) {
    if (output.lods <= 1)
      throw Error("command line", "--lod-ratio", "needs levels of detail: give --lods N (N >= 2) or the scene's output.lods");
    output.lodRatio = float(options.ratio);
    output.lodTriangles.clear();
  }
}

}  // namespace tendril::cli
