#pragma once
// A finalized scene laid out for memory-mapping, so that every actor on a host shares one copy of the
// per-triangle arrays (vertices, indices, materials, normals, areas, light probabilities) through the page cache
// instead of each building its own. Made on the host from the shipped scene (scene_file.hpp) by the first actor
// that needs it, next to the cached file; never shipped. Native byte order (it never leaves the host):
//   header (kHeaderSize bytes): "LFIMAGE2", u32 byte-order mark, u32 version, the shipped scene's hash (16 chars),
//     u64 triangles, u64 vertices, u32 materials, u32 point lights, u32 emitters, u32 textures, u32 corner normals
//     present, u32 corner uvs present, u32 corner tangents present, u64 texel bytes, f32 bounds lo[3] hi[3], f32
//     epsilon, u64 offset of each array (vertices, triangles, material ids, normals, areas, light pdf, corner
//     normals, corner uvs, corner tangents, the opaque-first order, its corners, texels, the small part), u64 size
//     of the small part, u32 opaque-first order present, u64 how many of it are opaque everywhere
//   the arrays, each at a 64-byte boundary; the vertex array is followed by at least 16 bytes (Embree reads
//     vertices with 16-byte loads); the opaque-first order (Scene::opaque_first: u32 triangles, then their corners
//     as u32 triples) only for a scene with cut-outs; the texels are every texture's, one after another
//   the small part: textures (u32 path length, path, u32 width, height, channels, u8 linear, u64 offset in the texels),
//     materials (as in scene_file), point lights, emitters (u32), light cdf and pdf (f32), u64 environment size and
//     the environment's binary form (Environment::write; size 0: none)
// Mapping checks every size, offset and index against the file, so a damaged image is refused (and remade), never
// read out of bounds.
#include <string>

#include "core/result.hpp"
#include "render/scene/scene.hpp"

namespace lf {

class SceneImage {
 public:
  static std::string encode(const Scene& scene, const std::string& hash);
  // Maps an image made for the shipped scene `hash`; the scene keeps the mapping alive.
  static Result<Scene> map(const std::string& path, const std::string& hash, const std::string& what);
};

// The scene of a cached shipped file (`shipped`, named by `hash`), shared with every other actor of this host:
// maps `shipped`.image, first making it (under a lock, so that concurrent actors make it once and all map the
// same file) when it is missing or damaged. Falls back to a private copy when the image cannot be written.
Result<Scene> load_shared_scene(const std::string& shipped, const std::string& hash, const std::string& what);

}  // namespace lf
