// The per-frame instance data the GPU turns into plant geometry (seed 000 §6): one branch
// instance per skeleton node, from which the vertex shader builds a generalised cylinder, and
// one leaf instance per leaf, which it expands into a curved, textured blade. Building these is
// plain CPU work over a PlantModel, kept apart from OpenGL so it can be tested and timed alone.
//
// Joints: a node's end ring and its continuing child's start ring are computed once and
// shared, bit for bit (same centre, radius, plane and angular reference), so consecutive
// segments join without gaps or cracks. The ring plane at a joint bisects the two segment
// directions (a mitre), and the angular reference is parallel-transported along each chain so
// that cylinders do not twist when the nodes' frames spin about their axes.
#pragma once

#include "tendril/plant/plant_model.h"
#include "tendril/render/render_scene.h"

#include <cstdint>
#include <span>
#include <vector>

namespace tendril::render {

struct GpuVec4 {
  float x = 0.0f, y = 0.0f, z = 0.0f, w = 0.0f;
};

enum BranchCaps : uint32_t {
  kCapStart = 1u << 0,  // close the segment's start (a root or a branch that does not join)
  kCapEnd = 1u << 1,    // close the segment's end (no continuing child)
};

// 7 × vec4, matching the branch vertex shader's instance attributes.
struct BranchInstance {
  GpuVec4 start;     // start ring centre (m), start radius (m)
  GpuVec4 end;       // end ring centre, end radius
  GpuVec4 startAxis; // unit normal of the start ring plane, bark v at the start
  GpuVec4 startRef;  // unit vector in the start ring plane at angle 0, bark v at the end
  GpuVec4 endAxis;   // unit normal of the end ring plane, BranchCaps bits
  GpuVec4 endRef;    // unit vector in the end ring plane at angle 0, bark texture layer
  GpuVec4 color;     // linear RGB albedo over the bark texture's mean colour, highlight (0 or 1)
};
static_assert(sizeof(BranchInstance) == 7 * 16);

// 4 × vec4, matching the leaf vertex shader's instance attributes.
struct LeafInstance {
  GpuVec4 base;       // where the blade starts (attachment moved `petiole` along leaf +Y), bend (rad)
  GpuVec4 halfWidth;  // leaf +X times half the blade width, texture layer
  GpuVec4 along;      // leaf +Y times the blade length, highlight (0 or 1)
  GpuVec4 tint;       // linear RGB multiplied with the texture, unused
};
static_assert(sizeof(LeafInstance) == 4 * 16);

// A primitive mesh placed in the world (the graph model's shapes): 5 × vec4, matching the
// primitive vertex shader's instance attributes.
struct PrimitiveInstance {
  GpuVec4 worldFromPrimitive[4];  // columns of worldFromNode · nodeFromPrimitive
  GpuVec4 color;                  // linear RGB of its PrimitiveMesh, highlight (0 or 1)
};
static_assert(sizeof(PrimitiveInstance) == 5 * 16);

// Colour for stress s in [0, 1]: blue → red through violet (seed 000 fig. 6, 10).
Vec3 stressColor(float stress);

// Appends one instance per node of `view.model`. `barkLayer` is the bark texture's layer and
// `barkMean` its mean colour: the albedo is divided by it so that the texture adds detail
// without changing the material's average colour. Bark v advances by arc length over the
// local circumference, so bark texels stay square.
void appendBranchInstances(const PlantView& view, float barkLayer, const Vec3& barkMean,
                           std::vector<BranchInstance>& out);

// Appends one instance per leaf; `shapeLayer[s]` is the texture layer of leaf shape id s,
// `shapeAspect[s]` its width / length and `shapeTint[s]` its tint (every id in use must be
// covered).
void appendLeafInstances(const PlantView& view, std::span<const float> shapeLayer, std::span<const float> shapeAspect,
                         std::span<const Vec3> shapeTint, std::vector<LeafInstance>& out);

// What a plant's instances take from the renderer's texture arrays, resolved beforehand on the
// thread that owns them (a layer lookup may load a texture).
struct PlantMaterial {
  float barkLayer = 0.0f;
  Vec3 barkMean = Vec3::Constant(0.5f);
  std::vector<float> shapeLayer;   // per leaf shape id, as appendLeafInstances takes them
  std::vector<float> shapeAspect;
  std::vector<Vec3> shapeTint;
};

// Replaces `branches` and `leaves` with the instances of every plant in `views`, plant after
// plant: bit for bit what appendBranchInstances and appendLeafInstances called on each view in
// turn give, but the plants are built in parallel. materials[i] belongs to views[i]; a view
// without a model adds nothing.
void buildPlantInstances(std::span<const PlantView> views, std::span<const PlantMaterial> materials,
                         std::vector<BranchInstance>& branches, std::vector<LeafInstance>& leaves);

// Appends one instance per primitive of `view.model` to perMesh[its mesh index] (perMesh is
// resized to the plant's mesh count). Primitives on selected nodes are highlighted.
void appendPrimitiveInstances(const PlantView& view, std::vector<std::vector<PrimitiveInstance>>& perMesh);

}  // namespace tendril::render
