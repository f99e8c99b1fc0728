// GLSL 4.10 core sources of the renderer (each program is "#version 410 core", its defines,
// then the pieces below). See renderer.h for what each pass draws.
#pragma once

namespace tendril::render::shaders {

// Fragment-side lighting shared by every lit surface: hemispheric ambient, Blinn-Phong from up
// to 8 directional / point lights, leaf translucency, variance shadow lookup (Donnelly &
// Lauritzen 2006), selection highlight, ACES tone mapping and sRGB encoding.
extern const char* const kLighting;

// Branches: a generalised cylinder per instance, built from gl_VertexID (seed 000 §6).
extern const char* const kBranchVertex;
extern const char* const kBranchFragment;
// Leaves: a cupped, bent blade per instance, alpha-tested against its texture layer.
extern const char* const kLeafVertex;
extern const char* const kLeafFragment;
// Obstacles: positions only; flat normals from screen-space derivatives.
extern const char* const kObstacleVertex;
extern const char* const kObstacleFragment;
// Plant primitives: instanced meshes with a world matrix each, flat normals like obstacles.
extern const char* const kPrimitiveVertex;
extern const char* const kPrimitiveFragment;
// Stroke points: instanced unit spheres.
extern const char* const kStrokeVertex;
extern const char* const kStrokeFragment;
// Gizmo and grid lines: unlit screen-space quads, one instance per line.
extern const char* const kLineVertex;
extern const char* const kLineFragment;

// Shadow pass: writes the first two moments of light-space depth (define ALPHA_TEST for
// leaves, with the leaf vertex shader).
extern const char* const kMomentsFragment;
// Separable Gaussian blur of the moments (full-screen triangle).
extern const char* const kFullscreenVertex;
extern const char* const kBlurFragment;

}  // namespace tendril::render::shaders
