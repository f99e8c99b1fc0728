// Wavefront .obj export: <name>.obj, <name>.mtl and the textures beside them
// (<name>_bark.png, <name>_leaf0.png, <name>_leaf1.png, ..., <name>_tex0.png for primitive
// textures; .jpg for JPEG files passed through).
//
// One `o` per plant or extra mesh and one `g` + `usemtl` per part (bark, leaves-<shape>,
// primitives); every part has v, vn and (when it has them) vt records. Leaf materials set
// map_Kd and map_d to the leaf texture (its alpha is the cut-out). Numbers are printed in the
// shortest form that reads back to the same float. Every file is replaced atomically.
//
// Plants with levels of detail (ExportObject::lods) are named <plant>_LOD0 in <name>.obj, and
// each lower level k is written to <name>_LOD<k>.obj (objLodPath) with the plants that have it,
// named <plant>_LOD<k>, using the same <name>.mtl.
#pragma once

#include "tendril/io/export_model.h"
#include "tendril/io/export_scene.h"

#include <filesystem>

namespace tendril::io {

void writeObj(const ExportScene& scene, const std::filesystem::path& path, const ExportOptions& options = {});
void writeObj(const ExportModel& model, const std::filesystem::path& path);

// <dir>/<stem>_LOD<level><ext>: where level `level` (>= 1) of the plants of `path` goes.
std::filesystem::path objLodPath(const std::filesystem::path& path, size_t level);

}  // namespace tendril::io
