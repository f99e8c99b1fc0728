#include "tendril/env/mesh_import.h"

#include "tendril/core/error.h"

#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <fstream>
#include <sstream>
#include <system_error>

namespace tendril::env {
namespace {

int plyTypeSize(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

// Assimp fills a PLY whose data stops early with zeros instead of failing. Walk the elements
// the header declares through the data (binary or ASCII) and report where the file runs out.
void checkPlyStructure(const std::string& name, const std::string& data) {
  if (data.compare(0, 3, "ply") != 0) return;
  size_t headerEnd = data.find("end_header");
  if (headerEnd == std::string::npos) throw Error(name, "", "PLY header has no end_header");
  size_t body = data.find('\n', headerEnd);
  body = (body == std::string::npos) ? data.size() : body + 1;
  struct Property {
    int size = 0;       // scalar size, or list item size
    int countSize = 0;  // > 0 for list properties
  };
  struct Element {
    std::string name;
    uint64_t count = 0;
    std::vector<Property> props;
  };
  std::vector<Element> elements;
  std::string format;
  std::istringstream header(data.substr(0, headerEnd));
  std::string line;
  int lineNo = 0;
  while (std::getline(header, line)) {
    ++lineNo;
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      ls >> format;
    } else if (word == "element") {
      Element e;
      if (!(ls >> e.name >> e.count)) throw Error(name, fmt::format("{}", lineNo), "bad PLY element line");
      elements.push_back(e);
    } else if (word == "property") {
      if (elements.empty()) throw Error(name, fmt::format("{}", lineNo), "PLY property before any element");
      std::string type;
      ls >> type;
      Property pr;
      if (type == "list") {
        std::string countType, itemType;
        ls >> countType >> itemType;
        pr.countSize = plyTypeSize(countType);
        pr.size = plyTypeSize(itemType);
        if (!pr.countSize || !pr.size) throw Error(name, fmt::format("{}", lineNo), "unknown PLY list type");
      } else {
        pr.size = plyTypeSize(type);
        if (!pr.size) throw Error(name, fmt::format("{}", lineNo), "unknown PLY property type \"" + type + "\"");
      }
      elements.back().props.push_back(pr);
    }
  }
  auto truncated = [&](const Element& e, uint64_t i) {
    return Error(name, "", fmt::format("truncated PLY: the data ends inside {} {} of {}", e.name, i, e.count));
  };
  if (format == "ascii") {
    std::istringstream in(data.substr(body));
    std::string token;
    for (const Element& e : elements)
      for (uint64_t i = 0; i < e.count; ++i)
        for (const Property& pr : e.props) {
          uint64_t n = 1;
          if (pr.countSize) {
            if (!(in >> n)) throw truncated(e, i);
          }
          for (uint64_t k = 0; k < n; ++k)
            if (!(in >> token)) throw truncated(e, i);
        }
    return;
  }
  bool little = format == "binary_little_endian";
  if (!little && format != "binary_big_endian") throw Error(name, "", "unknown PLY format \"" + format + "\"");
  size_t pos = body;
  for (const Element& e : elements)
    for (uint64_t i = 0; i < e.count; ++i)
      for (const Property& pr : e.props) {
        if (!pr.countSize) {
          pos += pr.size;
          if (pos > data.size()) throw truncated(e, i);
          continue;
        }
        if (pos + pr.countSize > data.size()) throw truncated(e, i);
        uint64_t n = 0;
        for (int b = 0; b < pr.countSize; ++b) {
          uint64_t byte = static_cast<uint8_t>(data[pos + (little ? b : pr.countSize - 1 - b)]);
          n |= byte << (8 * b);
        }
        pos += pr.countSize + n * pr.size;
        if (pos > data.size()) throw truncated(e, i);
      }
}

}  // namespace

TriangleMesh loadMeshFile(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw Error(name, "", "mesh file does not exist");
  if (std::filesystem::is_directory(path, ec)) throw Error(name, "", "is a directory, not a mesh file");
  if (std::filesystem::file_size(path, ec) == 0 || ec) throw Error(name, "", "mesh file is empty");

  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".ply") {
    std::ifstream in(path, std::ios::binary);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    checkPlyStructure(name, data);
  }

  Assimp::Importer importer;
  // No Assimp post-processing: Debian's build aborts on internal assertions when a step
  // (e.g. triangulation) meets data a loader half-read from a broken file. We validate every
  // index ourselves, apply node transforms and triangulate polygons as fans.
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(name, 0);
  } catch (const std::exception& e) {
    throw Error(name, "", fmt::format("cannot read mesh: {}", e.what()));
  }
  if (!scene) {
    std::string why = importer.GetErrorString();
    throw Error(name, "", fmt::format("cannot read mesh: {}", why.empty() ? "unknown format" : why));
  }
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode)
    throw Error(name, "", "cannot read mesh: the file is incomplete or broken");

  TriangleMesh out;
  auto addMesh = [&](unsigned mi, const aiMatrix4x4& worldFromMesh) {
    if (mi >= scene->mNumMeshes || !scene->mMeshes[mi])
      throw Error(name, fmt::format("mesh {}", mi), "node refers to a missing mesh");
    const aiMesh* mesh = scene->mMeshes[mi];
    if (!mesh->mVertices || mesh->mNumVertices == 0) return;
    uint32_t base = static_cast<uint32_t>(out.positions.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      aiVector3D p = worldFromMesh * mesh->mVertices[v];
      Vec3 q(p.x, p.y, p.z);
      if (!isFinite(q)) throw Error(name, fmt::format("mesh {} vertex {}", mi, v), "vertex position is not finite");
      out.positions.push_back(q);
    }
    if (!mesh->mFaces) return;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices < 3) continue;  // points and lines are not surfaces to climb
      if (!face.mIndices) throw Error(name, fmt::format("mesh {} face {}", mi, f), "face has no indices");
      for (unsigned k = 0; k < face.mNumIndices; ++k)
        if (face.mIndices[k] >= mesh->mNumVertices)
          throw Error(name, fmt::format("mesh {} face {}", mi, f), "vertex index out of range");
      for (unsigned k = 1; k + 1 < face.mNumIndices; ++k)
        out.indices.insert(out.indices.end(), {base + face.mIndices[0], base + face.mIndices[k],
                                               base + face.mIndices[k + 1]});
    }
  };
  // Depth-first over the node hierarchy, accumulating transforms (glTF and FBX place meshes
  // through nodes). A depth limit guards against cyclic or absurd hierarchies.
  struct Item {
    const aiNode* node;
    aiMatrix4x4 parentFromWorld;
    int depth;
  };
  std::vector<Item> stack = {{scene->mRootNode, aiMatrix4x4(), 0}};
  while (!stack.empty()) {
    Item it = stack.back();
    stack.pop_back();
    if (it.depth > 256) throw Error(name, "", "cannot read mesh: node hierarchy is too deep");
    aiMatrix4x4 worldFromNode = it.parentFromWorld * it.node->mTransformation;
    for (unsigned i = 0; i < it.node->mNumMeshes; ++i) addMesh(it.node->mMeshes[i], worldFromNode);
    for (unsigned c = it.node->mNumChildren; c-- > 0;)
      if (it.node->mChildren[c]) stack.push_back({it.node->mChildren[c], worldFromNode, it.depth + 1});
  }
  if (out.indices.empty()) throw Error(name, "", "mesh file contains no triangles");
  return out;
}

}  // namespace tendril::env
