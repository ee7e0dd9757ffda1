#pragma once
// A finished scene in a compact binary form, for shipping it to hosts once and caching it there: geometry,
// materials, textures and lights, exactly as the director loaded them, so that an actor rebuilds the same scene
// bit for bit without the OBJ file (or its MTL and images) and without parsing anything. Little-endian:
//   "LFSCENE11"
//   u32 textures; each: u32 path length, path, u32 width, height, channels, u8 linear, u32 deflated size, the texels (the
//     whole mip pyramid, render/scene/scene.hpp) deflated (zlib)
//   u32 materials; each: u32 name length, name, f32 kd[3] ke[3] ks[3], f32 ns, f32 ior, u8 type, i32 kd_map,
//     i32 alpha_map, f32 kr[3] tf[3], f32 metallic, f32 roughness, i32 metallic_map, i32 roughness_map, i32 normal_map,
//     f32 normal_scale, i32 emission_map, f32 transmission
//   u32 triangles; f32 corners[9 n] (a b c per triangle); u32 material[n]
//   u8 vertex normals present; if so f32 normals[9 n]
//   u8 texture coordinates present; if so f32 uvs[6 n]
//   u8 tangents present; if so f32 tangents[12 n] (direction[3], sign per corner)
//   u32 point lights; each: f32 position[3], intensity[3], axis[3], cos_inner, cos_outer (cos_outer < -1: no spot)
//   u32 environment size (0: none); the environment's binary form (render/lights/environment.hpp: Environment::write)
#include <cstdint>
#include <string>
#include <string_view>

#include "core/result.hpp"
#include "render/scene/scene.hpp"

namespace lf {

std::string scene_to_bytes(const Scene& scene);
// `what` names the source in errors and in the scene's own messages.
Result<Scene> scene_from_bytes(std::string_view bytes, const std::string& what);
// The content hash a cached scene is named by: 16 hex digits (64-bit FNV-1a), enough to tell scenes apart, not a
// defence against forgery (CURVE keeps strangers off the links that carry it).
std::string content_hash(std::string_view bytes);
// Reads a cached scene file (memory-mapped) and checks it against `hash`.
Result<Scene> load_cached_scene(const std::string& path, const std::string& hash, const std::string& what);

}  // namespace lf
