#include "tendril/models/plant_support.h"

namespace tendril::models {

void appendSupport(const plant::PlantModel& plant, uint32_t plantIndex, std::vector<env::StemTube>& tubes,
                   std::vector<env::ShadeTriangle>& shade) {
  const size_t n = plant.nodeCount();
  // The segment continuing a node is its first child (parents come before children).
  std::vector<int32_t> next(n, -1);
  for (size_t i = 0; i < n; ++i) {
    const int32_t p = plant.parent[i];
    if (p >= 0 && next[size_t(p)] < 0) next[size_t(p)] = int32_t(i);
  }
  tubes.reserve(tubes.size() + n);
  for (size_t i = 0; i < n; ++i) {
    env::StemTube t;
    t.a = plant.position[i];
    t.b = plant.tip(i);
    t.ra = plant.radius[i];
    t.rb = next[i] >= 0 ? plant.radius[size_t(next[i])] : plant.radius[i];
    t.plant = plantIndex;
    t.node = uint32_t(i);
    tubes.push_back(t);
  }
  // Each blade as one triangle of the area its outline fills, about half its quad's, as a leaf
  // does: its base as wide as the blade, from the petiole's end, its apex at the blade's tip.
  shade.reserve(shade.size() + plant.leafCount());
  for (size_t l = 0; l < plant.leafCount(); ++l) {
    const Quat rotation = plant.leafWorldRotation(l);
    const Vec3 y = rotation * Vec3::UnitY();
    const float size = plant.leafSize[l];
    const Vec3 halfWidth = (0.5f * size * plant.leafAspect(l)) * (rotation * Vec3::UnitX());
    const Vec3 base = plant.leafWorldPosition(l) + plant.leafPetiole[l] * y;
    shade.push_back({base - halfWidth, base + halfWidth, base + size * y});
  }
}

}  // namespace tendril::models
