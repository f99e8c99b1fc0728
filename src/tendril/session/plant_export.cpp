#include "tendril/session/plant_export.h"

namespace tendril::session {

io::ExportOptions exportOptions(const scene::OutputSettings& output) {
  io::ExportOptions options;
  options.mesh.radialSegments = output.radialSegments;
  options.mesh.subdivisions = output.subdivisions;
  return options;
}

io::ExportScene exportScene(const Session& session, const std::string& source) {
  io::ExportScene out;
  out.plants = session.plants();
  for (const plant::PlantModel& p : out.plants) plant::validate(p, source);
  if (session.scene().output.includeObstacles) {
    const env::Environment& env = session.environment();
    for (uint32_t id = 0; id < env.obstacleCount(); ++id) {
      const env::ObstacleInfo& info = env.obstacle(id);
      io::NamedMesh m{info.name, env.obstacleMesh(id), info.color};
      for (Vec3& v : m.mesh.positions) v = info.worldFromLocal.applyPoint(v);
      out.meshes.push_back(std::move(m));
    }
  }
  return out;
}

}  // namespace tendril::session
