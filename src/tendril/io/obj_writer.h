// Wavefront .obj export: <name>.obj, <name>.mtl and the textures beside them
// (<name>_bark.png, <name>_leaf0.png, <name>_leaf1.png, ..., <name>_tex0.png for primitive
// textures; .jpg for JPEG files passed through).
//
// One `o` per plant or extra mesh and one `g` + `usemtl` per part (bark, leaves-<shape>,
// primitives); every part has v, vn and (when it has them) vt records. Leaf materials set
// map_Kd and map_d to the leaf texture (its alpha is the cut-out). Numbers are printed in the
// shortest form that reads back to the same float. Every file is replaced atomically.
#pragma once

#include "tendril/io/export_model.h"
#include "tendril/io/export_scene.h"

#include <filesystem>

namespace tendril::io {

void writeObj(const ExportScene& scene, const std::filesystem::path& path, const ExportOptions& options = {});
void writeObj(const ExportModel& model, const std::filesystem::path& path);

}  // namespace tendril::io
