// A small software rasteriser for looking at graph examples without a GPU: the plant's meshes
// (mesh::buildPlantMesh) through a pinhole camera, z-buffered, Lambert-lit, leaf textures
// alpha-tested, 2×2 supersampled.
#pragma once

#include "tendril/io/image.h"
#include "tendril/plant/plant_model.h"

namespace tendril::graphtest {

struct PreviewCamera {
  Vec3 eye = Vec3(3, 2, 4);
  Vec3 target = Vec3(0, 1, 0);
  float fov = 40.0f;  // degrees, vertical
};

// A camera looking at the plant's bounds from the front-right, slightly above.
PreviewCamera frameBounds(const plant::PlantModel& plant, float fov = 35.0f);

io::Image renderPreview(const plant::PlantModel& plant, const PreviewCamera& camera, int width, int height,
                        const Vec3& lightDirection = Vec3(-0.4f, -1.0f, -0.5f));

}  // namespace tendril::graphtest
