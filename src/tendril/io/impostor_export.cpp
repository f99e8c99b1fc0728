// The impostor level of the exporters' model (io/impostor.h, export_model.h).
#include "tendril/core/error.h"
#include "tendril/io/export_model.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>

namespace tendril::io {

std::shared_ptr<ImpostorBaker> impostorBakerFor(const ExportOptions& options) {
  if (!options.impostor.enabled) return nullptr;
  validateImpostorSettings(options.impostor, "export options");
  std::shared_ptr<ImpostorBaker> baker = installedImpostorBaker();
  if (!baker)
    throw Error("export options", "impostor",
                "no impostor baker is installed (baking needs the renderer: use the tendril CLI, the studio or the "
                "Python module)");
  return baker;
}

void addImpostors(const ExportScene& scene, const ExportOptions& options, ExportModel& model) {
  const std::shared_ptr<ImpostorBaker> baker = impostorBakerFor(options);
  if (!baker) return;
  const size_t plants = scene.plants.size();
  model.impostors.assign(plants, Impostor{});  // sized once: parts point into it
  std::map<int, Image> decoded;                // by image index
  auto imageOf = [&](int texture) -> const Image* {
    if (texture < 0) return nullptr;
    const int image = model.textures[size_t(texture)].image;
    auto it = decoded.find(image);
    if (it == decoded.end())
      it = decoded.emplace(image, decodeImage(model.images[size_t(image)].image.bytes, model.images[size_t(image)].spec))
               .first;
    return &it->second;
  };
  for (size_t i = 0; i < plants; ++i) {
    ExportObject& object = model.objects[i];
    if (object.parts.empty()) continue;
    std::vector<ImpostorSurface> surfaces;
    for (const ExportPart& part : object.parts) {
      const ExportMaterial& m = model.materials[size_t(part.material)];
      ImpostorSurface s;
      s.mesh = part.mesh;
      s.baseColor = m.baseColor;
      s.texture = imageOf(m.texture);
      s.repeat = m.texture >= 0 && model.textures[size_t(m.texture)].repeat;
      s.alphaMask = m.alphaMask;
      s.primitive = part.source == PartSource::Primitive;
      surfaces.push_back(s);
    }
    Impostor& impostor = model.impostors[i];
    impostor = buildImpostor(surfaces, options.impostor, *baker, object.name);
    if (impostor.quads.empty()) continue;
    // Wind: every vertex sways with the plant's root node (docs/export.md, "Impostor").
    if (scene.plants[i].nodeCount() > 0) impostor.mesh.nodeIds.assign(impostor.mesh.positions.size(), 0u);

    auto addImage = [&](const Image& img, const std::string& role) {
      EncodedImage e;
      e.mimeType = "image/png";
      e.bytes = encodePng(img);
      e.width = img.width;
      e.height = img.height;
      model.images.push_back({fmt::format("{}-impostor-{}.png", object.name, role), std::move(e)});
      model.textures.push_back({int(model.images.size() - 1), false});
      return int(model.textures.size() - 1);
    };
    ExportMaterial m;
    m.kind = ExportMaterial::Kind::Impostor;
    m.name = "impostor";
    for (int k = 2; std::any_of(model.materials.begin(), model.materials.end(),
                                [&](const ExportMaterial& o) { return o.name == m.name; });
         ++k)
      m.name = fmt::format("impostor-{}", k);
    m.roughness = 0.8f;
    m.texture = addImage(impostor.color, "color");
    m.normalTexture = addImage(impostor.normal, "normal");
    m.alphaMask = true;
    m.doubleSided = true;
    model.materials.push_back(std::move(m));

    ExportPart part;
    part.name = "impostor";
    part.mesh = &impostor.mesh;
    part.material = int(model.materials.size() - 1);
    part.source = PartSource::Mesh;
    part.tangents = &impostor.tangents;
    std::vector<size_t> triangles{model.plantMeshes[i].triangleCount()};
    for (const mesh::LodLevel& level : model.plantLods[i]) triangles.push_back(level.triangles);
    triangles.push_back(impostor.mesh.triangleCount());
    object.lods.push_back({part});
    object.screenCoverage = mesh::lodScreenCoverage(triangles);
  }
}

}  // namespace tendril::io
