// glTF 2.0 binary export (.glb). tinygltf builds and serialises the glTF JSON; the binary
// chunk is streamed straight from the meshes into the file (no second copy of the geometry).
//
// One scene; one node per plant (named after it) and per extra mesh. A plant's mesh has one
// primitive per part: "bark" (PBR metallic-roughness, the bark texture repeating), one per
// leaf shape (alphaMode MASK with cutoff 0.5, double-sided, the leaf texture clamped, the
// shape's tint as baseColorFactor) and one per primitive material. Attributes: POSITION (with
// min/max), unit NORMAL, TEXCOORD_0 (glTF's v points down the image, so v is flipped from the
// mesh convention) and, on plant parts, _NODE_ID: per vertex the skeleton node it was built
// from (TriangleMesh::nodeIds; a float scalar holding an exact integer, as glTF forbids unsigned
// int for application-specific attributes; docs/skeleton-format.md); with engine wind data
// (ExportScene::wind, io/wind_attributes.h) also COLOR_0 (float RGBA: branch level, phase,
// natural period, leaf flag), _WIND_PIVOT and _WIND_AXIS (float VEC3), docs/engine-wind.md;
// with Pivot Painter textures (ExportScene::pivotPainter, io/pivot_painter.h) also TEXCOORD_1,
// the UV of the vertex's element's pixel (and a TEXCOORD_0 of zeros on a part without uvs);
// indices are uint16 when a part has fewer than 65536 vertices, else uint32.
// Images are embedded as PNG/JPEG buffer views. Nothing unused is written, so the Khronos
// validator reports no errors and no warnings. The bytes depend only on the input, not on the
// thread count. The file is replaced atomically (atomic_file.h).
//
// writeGlb(scene) streams: plants are meshed a few at a time, in parallel, into meshes reused
// from plant to plant, and written in order; the JSON chunk is written last into room reserved
// for it before the geometry (an upper bound computed from the scene), padded with spaces. It
// holds one plant's meshes per thread instead of the whole scene's, and its geometry and JSON
// are those writeGlb(buildExportModel(scene)) writes; only the JSON chunk's padding differs.
#pragma once

#include "tendril/io/export_model.h"
#include "tendril/io/export_scene.h"

#include <filesystem>

namespace tinygltf {
class Model;
}

namespace tendril::io {

// Appends the model's materials, samplers (one per wrap mode in use) and textures to a glTF
// being built; images (texture sources) are left to the caller, which owns the binary buffer.
void appendMaterialsAndTextures(const ExportModel& model, tinygltf::Model& gltf);

void writeGlb(const ExportScene& scene, const std::filesystem::path& path, const ExportOptions& options = {});
// `wind`: per plant (object i for plant i) its engine wind table, as ExportScene::wind;
// `pivot`: per plant its Pivot Painter grid, as ExportScene::pivotPainter (an Error for a plant
// with instanced shapes).
void writeGlb(const ExportModel& model, const std::filesystem::path& path, const WindTables* wind = nullptr,
              const PivotPainterGrids* pivot = nullptr);

}  // namespace tendril::io
