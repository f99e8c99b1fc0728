#include "tendril/env/mesh_import.h"

#include "tendril/core/error.h"

#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>

namespace tendril::env {
namespace {

std::atomic<uint64_t> gMaxFileBytes{MeshImportLimits{}.maxFileBytes};
std::atomic<uint64_t> gMaxTriangles{MeshImportLimits{}.maxTriangles};

Error tooManyTriangles(const std::string& name, uint64_t triangles, const char* what) {
  return Error(name, "", fmt::format("{} {} triangles, more than the {} a mesh may have (--max-mesh-triangles)", what,
                                     triangles, gMaxTriangles.load()));
}

// OFF: "OFF" (or COFF, NOFF, ...), then the vertex, face and edge counts, then the vertices and
// faces, one per line. Assimp allocates for the declared counts before reading them, and it
// quietly accepts face indices past the vertices: check that the file can hold what it
// declares (an ASCII vertex takes at least "0 0 0\n", a face "3 0 1 2\n") and walk the faces.
void checkOffStructure(const std::string& name, const std::string& data) {
  // The file's tokens with their line numbers, comments (# to the end of a line) left out.
  size_t pos = 0;
  int line = 1;
  auto next = [&](std::string& token) {
    token.clear();
    while (pos < data.size()) {
      const char c = data[pos];
      if (c == '#') {
        while (pos < data.size() && data[pos] != '\n') ++pos;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        if (c == '\n') ++line;
        ++pos;
      } else {
        break;
      }
    }
    while (pos < data.size() && !std::isspace(static_cast<unsigned char>(data[pos])) && data[pos] != '#') token += data[pos++];
    return !token.empty();
  };
  std::string token;
  // The keyword alone: [ST][C][N][4][n]OFF (Assimp reads "OFF3 ..." as "OFF" followed by counts,
  // found by fuzz/mesh, so anything else is refused here).
  auto keyword = [](const std::string& t) {
    return t.size() >= 3 && t.size() <= 8 && t.compare(t.size() - 3, 3, "OFF") == 0 &&
           t.find_first_not_of("STCN4n") >= t.size() - 3;
  };
  if (!next(token) || !keyword(token))
    throw Error(name, "1", fmt::format("an OFF file starts with \"OFF\" (or COFF, NOFF, ...), got \"{}\"", token.substr(0, 40)));
  const std::string magic = token;
  auto count = [&](const char* what) -> uint64_t {
    if (!next(token) || !std::isdigit(static_cast<unsigned char>(token[0])) || token.size() > 19 ||
        token.find_first_not_of("0123456789") != std::string::npos)
      throw Error(name, fmt::format("{}", line), fmt::format("OFF header: expected the {} count after \"{}\"", what, magic));
    return std::stoull(token);
  };
  const uint64_t vertices = count("vertex"), faces = count("face");
  count("edge");
  const uint64_t body = data.size() - pos;
  if (vertices > body / 6 || faces > body / 8 || vertices * 6 + faces * 8 > body)
    throw Error(name, "", fmt::format("OFF header declares {} vertices and {} faces, more than the file's {} bytes "
                                      "can hold", vertices, faces, data.size()));
  if (faces > gMaxTriangles.load()) throw tooManyTriangles(name, faces, "OFF header declares at least");
  if (magic != "OFF") return;  // colours, normals or texture coordinates per vertex: left to Assimp
  for (uint64_t v = 0; v < vertices; ++v)
    for (int k = 0; k < 3; ++k)
      if (!next(token)) throw Error(name, "", fmt::format("truncated OFF: the data ends inside vertex {} of {}", v, vertices));
  for (uint64_t f = 0; f < faces; ++f) {
    const int at = line;
    if (!next(token)) throw Error(name, "", fmt::format("truncated OFF: the data ends inside face {} of {}", f, faces));
    char* countEnd = nullptr;
    const uint64_t n = std::strtoull(token.c_str(), &countEnd, 10);
    // A face is a polygon: Assimp crashes on one of fewer than three vertices (found by fuzz/mesh).
    if (*countEnd != '\0' || token[0] == '-' || n < 3 || n > body)
      throw Error(name, fmt::format("{}", at),
                  fmt::format("face {}: \"{}\" is not a polygon's vertex count (3 or more)", f, token.substr(0, 40)));
    for (uint64_t k = 0; k < n; ++k) {
      if (!next(token)) throw Error(name, "", fmt::format("truncated OFF: the data ends inside face {} of {}", f, faces));
      char* end = nullptr;
      const unsigned long long index = std::strtoull(token.c_str(), &end, 10);
      if (*end != '\0' || token[0] == '-' || index >= vertices)
        throw Error(name, fmt::format("{}", at),
                    fmt::format("face {}: vertex index \"{}\" out of range (the file has {} vertices)", f, token, vertices));
    }
    // Colours may follow a face's indices on its line.
    while (pos < data.size() && data[pos] != '\n') ++pos;
  }
}

// STL: binary (an 80-byte header, the triangle count, then 50 bytes per triangle) or ASCII
// ("solid ..."; a binary file's header may start so too, then its size fits its count).
void checkStlHeader(const std::string& name, const std::filesystem::path& path, uint64_t size) {
  std::ifstream in(path, std::ios::binary);
  char head[84];
  if (!in.read(head, 84)) return;  // too short for either: Assimp says so
  uint32_t n = 0;
  std::memcpy(&n, head + 80, 4);
  const bool binary = std::strncmp(head, "solid", 5) != 0 || 84 + 50 * uint64_t(n) == size;
  if (!binary) {
    // ASCII: a facet takes well over 100 bytes.
    if (size / 100 > gMaxTriangles.load()) throw tooManyTriangles(name, size / 100, "ASCII STL of about");
    return;
  }
  if (84 + 50 * uint64_t(n) > size)
    throw Error(name, "", fmt::format("binary STL declares {} triangles, more than the file's {} bytes can hold", n, size));
  if (n > gMaxTriangles.load()) throw tooManyTriangles(name, n, "binary STL declares");
}

// OBJ: every face line is at least one triangle.
void checkObjFaces(const std::string& name, const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  uint64_t faces = 0;
  while (std::getline(in, line))
    if (line.size() > 1 && line[0] == 'f' && (line[1] == ' ' || line[1] == '\t') && ++faces > gMaxTriangles.load())
      throw tooManyTriangles(name, faces, "OBJ file has over");
}

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
  // "ply" on the first line, exactly (Assimp also takes "plY" and then loops forever on the
  // rest, found by fuzz/mesh).
  if (!(data.compare(0, 4, "ply\n") == 0 || data.compare(0, 5, "ply\r\n") == 0))
    throw Error(name, "1", "a PLY file starts with a line \"ply\"");
  // "end_header" on a line of its own (Debian's Assimp 5.2 loops forever on one followed by
  // anything else, found by fuzz/mesh).
  size_t headerEnd = data.find("\nend_header");
  if (headerEnd == std::string::npos) throw Error(name, "", "PLY header has no end_header");
  ++headerEnd;
  size_t body = headerEnd + 10;
  if (body < data.size() && data[body] == '\r') ++body;
  if (body < data.size() && data[body] != '\n')
    throw Error(name, "", "PLY header: end_header must be on a line of its own");
  body = std::min(body + 1, data.size());
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
    // Only the header's own keywords: Debian's Assimp 5.2 loops forever on a header line it
    // does not know (found by fuzz/mesh).
    if (lineNo == 1 ? word != "ply"
                    : !(word.empty() || word == "format" || word == "element" || word == "property" ||
                        word == "comment" || word == "obj_info"))
      throw Error(name, fmt::format("{}", lineNo),
                  lineNo == 1 ? "a PLY file starts with \"ply\""
                              : fmt::format("PLY header: unknown keyword \"{}\" (expected format, element, property, "
                                            "comment, obj_info or end_header)", word.substr(0, 40)));
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
  for (const Element& e : elements)
    if (e.name == "face" && e.count > gMaxTriangles.load()) throw tooManyTriangles(name, e.count, "PLY header declares at least");
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

void setMeshImportLimits(const MeshImportLimits& limits) {
  gMaxFileBytes = limits.maxFileBytes;
  gMaxTriangles = limits.maxTriangles;
}

MeshImportLimits meshImportLimits() { return {gMaxFileBytes.load(), gMaxTriangles.load()}; }

TriangleMesh loadMeshFile(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw Error(name, "", "mesh file does not exist");
  if (std::filesystem::is_directory(path, ec)) throw Error(name, "", "is a directory, not a mesh file");
  if (std::filesystem::file_size(path, ec) == 0 || ec) throw Error(name, "", "mesh file is empty");

  const uint64_t size = std::filesystem::file_size(path, ec);
  if (size > gMaxFileBytes.load())
    throw Error(name, "", fmt::format("mesh file is {} bytes, more than the {} a mesh file may have", size,
                                      gMaxFileBytes.load()));

  // What the header declares, against the file's size and the limits, before Assimp allocates
  // for it.
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".ply" || ext == ".off") {
    std::ifstream in(path, std::ios::binary);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (ext == ".ply") checkPlyStructure(name, data);
    else checkOffStructure(name, data);
  } else if (ext == ".stl") {
    checkStlHeader(name, path, size);
  } else if (ext == ".obj") {
    checkObjFaces(name, path);
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
      if (out.indices.size() / 3 + face.mNumIndices - 2 > gMaxTriangles.load())
        throw tooManyTriangles(name, out.indices.size() / 3 + face.mNumIndices - 2, "mesh has over");
      for (unsigned k = 1; k + 1 < face.mNumIndices; ++k)
        out.indices.insert(out.indices.end(), {base + face.mIndices[0], base + face.mIndices[k],
                                               base + face.mIndices[k + 1]});
    }
  };
  // Depth-first over the node hierarchy, accumulating transforms (glTF and FBX place meshes
  // through nodes). A depth limit guards against cyclic or absurd hierarchies, and a limit on
  // the nodes visited against a hierarchy that shares children (a few nodes listing the same
  // child twice at each level would be visited 2^depth times).
  struct Item {
    const aiNode* node;
    aiMatrix4x4 parentFromWorld;
    int depth;
  };
  std::vector<Item> stack = {{scene->mRootNode, aiMatrix4x4(), 0}};
  constexpr uint64_t kMaxVisits = uint64_t(1) << 20;
  uint64_t visits = 0;
  while (!stack.empty()) {
    if (++visits > kMaxVisits)
      throw Error(name, "", fmt::format("cannot read mesh: its node hierarchy places meshes more than {} times", kMaxVisits));
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
