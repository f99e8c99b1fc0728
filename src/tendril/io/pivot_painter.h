// Pivot Painter 2-style wind textures (issue 26 part 4; docs/export.md "Pivot Painter
// textures"): per plant, the engine wind data of every skeleton node (io/wind_attributes.h)
// as the pair of data textures Unreal's Pivot Painter 2 material functions read, one pixel per
// element, and per vertex the UV of its element's pixel.
//
// Elements are the plant's skeleton nodes, element i is node i: a vertex's element is its
// _NODE_ID, so that the textures hold exactly what the vertex's _WIND_PIVOT and _WIND_AXIS
// hold (a leaf is drawn about its node's pivot, as in the wind data). Element i is pixel
// (i mod width, i div width), row 0 the top row of the image; its UV (glTF TEXCOORD_1, Unreal's
// UV channel 1, the Pivot Painter 2 functions' default) is the pixel's centre,
// ((i mod width + ½) / width, (i div width + ½) / height).
//
// Both textures are in Unreal's frame (Z up, left-handed, centimetres), which Unreal's glTF
// importer gives the mesh: a glTF point (x, y, z) m is (100 x, 100 z, 100 y) cm there, a
// direction (x, y, z) is (x, z, y).
//   * "<stem>-<plant>-pp-pivot.exr", RGBA half float: RGB the pivot P (_WIND_PIVOT) in cm; A the
//     parent's element index, Pivot Painter 2's "Parent Index (Int as float)": the half whose
//     bits are index + 1024 (a root is its own parent).
//   * "<stem>-<plant>-pp-xaxis.png", RGBA 8 bit, linear: RGB the lever's direction
//     (_WIND_AXIS / |_WIND_AXIS|) as (v + 1) / 2; A the "X-Extent": the length of the node's
//     branch (the axis of one order it belongs to) as clamp(cm / 8, 1, 256) / 256, which the
//     Pivot Painter 2 functions decode as A × 2048 cm (8 cm to 20.48 m in steps of 8 cm).
#pragma once

#include "tendril/core/math.h"
#include "tendril/io/wind_attributes.h"
#include "tendril/plant/plant_model.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace tendril::io {

// A plant's texture size; width 0: the plant has no Pivot Painter data.
struct PivotPainterGrid {
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t elements = 0;
};
// Per plant (as ExportScene::plants); empty: none.
using PivotPainterGrids = std::vector<PivotPainterGrid>;

// The most elements a plant may have: the parent index's half float holds index + 1024 below
// the largest finite half (0x7BFF).
inline constexpr uint32_t kPivotPainterMaxElements = 0x7BFF - 1024 + 1;
// Unreal's units per metre.
inline constexpr float kPivotPainterCmPerMetre = 100.0f;

// The texture size for `elements` elements: width ⌈√n⌉, height ⌈n / width⌉ (no pixel row left
// empty). `source` and `plant` name the plant in the Error for more than
// kPivotPainterMaxElements.
PivotPainterGrid pivotPainterGrid(size_t elements, const std::string& source = "", const std::string& plant = "");
// Element `element`'s pixel centre as a glTF UV (v down the image).
Vec2 pivotPainterUv(uint32_t element, const PivotPainterGrid& grid);
// Element index ↔ the half-float bits of Pivot Painter 2's "Parent Index (Int as float)".
inline uint16_t packPivotPainterIndex(uint32_t index) { return static_cast<uint16_t>(index + 1024); }
inline uint32_t unpackPivotPainterIndex(uint16_t bits) { return uint32_t(bits) - 1024; }
// glTF frame (Y up, right-handed, m) → Unreal's (Z up, left-handed, cm), and back.
inline Vec3 unrealPoint(const Vec3& p) { return kPivotPainterCmPerMetre * Vec3(p.x(), p.z(), p.y()); }
inline Vec3 unrealDirection(const Vec3& d) { return Vec3(d.x(), d.z(), d.y()); }
inline Vec3 gltfPoint(const Vec3& p) { return Vec3(p.x(), p.z(), p.y()) / kPivotPainterCmPerMetre; }
inline Vec3 gltfDirection(const Vec3& d) { return Vec3(d.x(), d.z(), d.y()); }
// X-Extent: a length (m) as its 8-bit alpha, and the alpha back as Pivot Painter 2 reads it (m).
uint8_t encodePivotPainterExtent(float metres);
inline float decodePivotPainterExtent(uint8_t alpha) { return float(alpha) / 255.0f * 2048.0f / kPivotPainterCmPerMetre; }

// The two textures of one plant, row-major from the top row.
struct PivotPainterTextures {
  PivotPainterGrid grid;
  std::vector<std::array<uint16_t, 4>> pivot;  // half-float bits: pivot xyz (cm), packed parent index
  std::vector<std::array<uint8_t, 4>> xaxis;   // lever direction (v + 1) / 2, X-Extent
};

// The length of each node's branch (m): the sum of the lengths of the nodes of its axis (a node
// continues its parent's axis when it has the parent's order).
std::vector<float> branchLengths(const plant::PlantModel& plant);

// A plant's textures from its engine wind table (one record per node; wind::engineWindNodes).
// An Error naming `source` and the plant for a table of another size or too many nodes.
PivotPainterTextures pivotPainterTextures(const plant::PlantModel& plant, const std::vector<WindVertexNode>& wind,
                                          const std::string& source);

// The side files' paths for plant `name` next to `<dir>/<stem>.glb` (the name made safe for a
// file name: characters other than letters, digits, '.', '_' and '-' become '_').
std::filesystem::path pivotPainterPivotPath(const std::filesystem::path& dir, const std::string& stem,
                                            const std::string& name);
std::filesystem::path pivotPainterXAxisPath(const std::filesystem::path& dir, const std::string& stem,
                                            const std::string& name);

// Writes the textures (each atomically, atomic_file.h): the pivot texture as OpenEXR (RGBA
// half, ZIP compression), the axis texture as PNG. The same bytes for the same textures.
void writePivotPainterTextures(const PivotPainterTextures& textures, const std::filesystem::path& pivotExr,
                               const std::filesystem::path& xaxisPng);

}  // namespace tendril::io
