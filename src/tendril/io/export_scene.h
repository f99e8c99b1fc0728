// What the exporters write: plants (meshed on the way out) and extra named meshes such as
// obstacles, each with a plain material.
#pragma once

#include "tendril/core/triangle_mesh.h"
#include "tendril/io/impostor.h"
#include "tendril/io/pivot_painter.h"
#include "tendril/io/wind_attributes.h"
#include "tendril/mesh/lod.h"
#include "tendril/mesh/mesh_options.h"
#include "tendril/plant/plant_model.h"

#include <string>
#include <vector>

namespace tendril::io {

struct NamedMesh {
  std::string name;
  TriangleMesh mesh;                     // world space; normals computed when missing
  Vec3 color = Vec3(0.6f, 0.6f, 0.6f);  // linear RGB
};

struct ExportScene {
  std::vector<plant::PlantModel> plants;
  std::vector<NamedMesh> meshes;
  // Engine wind data per plant (wind::engineWindTables, docs/engine-wind.md): with a table for
  // plant i, the .glb gives its vertices COLOR_0, _WIND_PIVOT and _WIND_AXIS. Empty: none.
  WindTables wind;
  // Pivot Painter textures per plant (io/pivot_painter.h; session::writePivotPainterFiles
  // writes them): with a grid for plant i, the .glb gives its vertices TEXCOORD_1, the UV of
  // their element's (their node's) pixel. Empty: none. Not with ExportOptions::instancing.
  PivotPainterGrids pivotPainter;
};

struct ExportOptions {
  mesh::MeshOptions mesh;
  // Levels of detail per plant (mesh/lod.h); with more than one, every level (LOD0 too) is
  // written in vertex cache and fetch order.
  mesh::LodSettings lods;
  // Each plant's leaf textures packed into one atlas and its leaves (every level) one part with
  // one material, UVs remapped into the atlas (io/leaf_atlas.h).
  bool leafAtlas = false;
  // The .glb writes a graph plant's repeated primitive shapes once each, drawn at every copy by
  // EXT_mesh_gpu_instancing, where that makes the file smaller (io/instancing.h; LOD0 only).
  bool instancing = false;
  // Bark normal and roughness maps and leaf normal maps made with their textures
  // (io/material_maps.h; normalTexture, metallicRoughnessTexture; .obj norm, map_Pr).
  bool maps = false;
  // A last level of detail after the chain: the plant as a slab billboard cloud baked by the
  // installed ImpostorBaker (io/impostor.h); with it the .glb is written from one ExportModel
  // (not streamed). Without an installed baker, asking for it is an Error.
  ImpostorSettings impostor;
};

inline ExportOptions defaultExportOptions() { return {}; }

}  // namespace tendril::io
