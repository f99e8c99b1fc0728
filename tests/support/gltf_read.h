// Reading back what the exporters wrote, for the io tests: a .glb and its float attributes.
#pragma once

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace tendril::test {

// A .glb as tinygltf reads it (a failed load is a test failure, with tinygltf's message).
inline tinygltf::Model loadGlb(const std::filesystem::path& file) {
  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, file.string())) << err;
  return m;
}

// One float attribute of a primitive, `width` floats per vertex (empty when it has none).
inline std::vector<float> floatAttribute(const tinygltf::Model& m, const tinygltf::Primitive& prim,
                                         const std::string& name, int width) {
  auto it = prim.attributes.find(name);
  if (it == prim.attributes.end()) return {};
  const tinygltf::Accessor& a = m.accessors[size_t(it->second)];
  const tinygltf::BufferView& v = m.bufferViews[size_t(a.bufferView)];
  EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT) << name;
  EXPECT_EQ(tinygltf::GetNumComponentsInType(uint32_t(a.type)), width) << name;
  std::vector<float> out(a.count * size_t(width));
  std::memcpy(out.data(), m.buffers[size_t(v.buffer)].data.data() + v.byteOffset + a.byteOffset,
              out.size() * sizeof(float));
  return out;
}

}  // namespace tendril::test
