#pragma once
// Scene: triangles with materials, and the emitters among them. Built from a built-in scene (builtin_scenes.cpp) or
// an OBJ+MTL file via tinyobjloader (obj_scene.cpp), plus the lights a script adds (script_lights.cpp).
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/specs.hpp"
#include "core/result.hpp"
#include "render/lights/emitter_cutouts.hpp"
#include "render/lights/environment.hpp"
#include "render/lights/light_tree.hpp"
#include "render/math.hpp"

namespace tinyobj {
class ObjReader;
}  // namespace tinyobj

namespace lf {

struct Material {
  // metal_rough: glTF's metal-roughness model on a GGX microfacet distribution (render/shading/microfacet.hpp),
  // with kd (and kd_map) its base colour.
  enum class Type { diffuse, glossy, mirror, glass, metal_rough };
  std::string name;
  RGB kd;  // diffuse reflectance
  RGB ke;  // emitted radiance; non-zero makes every triangle of this material an area light
  Type type = Type::diffuse;
  RGB ks;         // glossy: Phong lobe reflectance; mirror: reflectance
  float ns = 0;   // glossy: Phong exponent
  float ior = 1.5f;  // glass: index of refraction
  RGB kr;            // diffuse and glossy: a perfect mirror term beside their lobes (MTL illum 3 with Kd)
  RGB tf{1, 1, 1};   // glass: what light entering it keeps, per channel (MTL Tf)
  float metallic = 0, roughness = 0.5f;  // metal_rough: glTF's metallicFactor and roughnessFactor (0 to 1)
  // metal_rough: the share of its dielectric part that is rough glass of index `ior` (glTF's
  // KHR_materials_transmission; render/shading/microfacet.hpp).
  float transmission = 0;
  // Textures (indices into Scene::textures(), -1 for none). kd_map replaces kd where the triangle has texture
  // coordinates; alpha_map cuts the surface out where its coverage is below one half (docs/decisions.md).
  int32_t kd_map = -1;
  int32_t alpha_map = -1;
  // metal_rough: one-channel linear textures the factors above multiply (glTF's metallicRoughnessTexture, its blue
  // and green channels; MTL map_Pm and map_Pr).
  int32_t metallic_map = -1;
  int32_t roughness_map = -1;
  // A tangent-space normal map (a `linear` three-channel texture; glTF's normalTexture, MTL norm), its x and y
  // scaled by normal_scale: it turns the shading normal (render/scene/surface.hpp).
  int32_t normal_map = -1;
  float normal_scale = 1;
  // An emission map (sRGB colour; glTF's emissiveTexture): ke times its colour where the triangle has texture
  // coordinates.
  int32_t emission_map = -1;
  bool emissive() const { return !is_black(ke); }
  bool specular() const { return type == Type::mirror || type == Type::glass; }
  // A diffuse or glossy surface that also reflects like a mirror (kr): its mirror term is the `specular` op's.
  bool has_mirror_term() const { return !specular() && !is_black(kr); }
  // Light passes through the surface along lobes that are not single directions (rough glass): such a point
  // gathers light from both sides.
  bool transmits() const { return type == Type::metal_rough && transmission > 0 && metallic < 1; }
  // A Lambert lobe of its own (diffuse and glossy materials with kd).
  bool has_lambert_lobe() const { return (type == Type::diffuse || type == Type::glossy) && !is_black(kd); }
  // A lobe the diffuse caches serve (the light-path check's D): a Lambert lobe, or a metal_rough material's base
  // under its coating or its conductor's multiply scattered light. Those two weigh light by its elevation alone,
  // which a cache's records keep in bands (render/shading/elevation_bands.hpp); the rest of a metal_rough
  // material (its specular lobe and rough glass) is a glossy lobe, the `glossy` op's (docs/decisions.md,
  // "Microfacet materials").
  bool has_diffuse_lobe() const {
    if (type != Type::metal_rough) return has_lambert_lobe();
    return metallic > 0 || (metallic < 1 && transmission < 1 && (!is_black(kd) || kd_map >= 0));
  }
};

// The MTL illum model and coefficients as a Material (docs/lua-api.md, "Materials"): illum 5, and 3 without Kd, are
// mirrors (Ks); 3 with Kd keeps Kd and adds Ks as a mirror term, shared with a Phong lobe where Ns > 0; 4, 6, 7 and
// 9 are glass (Ni, tinted by Tf where the file gives one); 2 with Ks > 0 and Ns > 0 glossy; anything else diffuse.
// Kd + Ks is scaled to at most 1 per channel so that no surface creates energy.
Material material_from_mtl(std::string name, RGB kd, RGB ks, RGB ke, float ns, float ni, int illum, RGB tf = {});

struct Bounds {
  Vec3 lo, hi;
  float diagonal() const { return length(hi - lo); }
};
// The box around `points` (not empty).
Bounds bounds_of(std::span<const Vec3> points);

// A texture as the scene keeps it: 8-bit texels, row-major, top row first (as image files store them), as a mip
// pyramid: the full image, then each level half the size of the one before (2x2 box filter, in linear values),
// down to 1x1, one after another. A map_Kd keeps 3 channels (sRGB-encoded colour), a map_d 1 (linear coverage).
struct Texture {
  std::string path;  // as the MTL named it
  uint32_t width = 0, height = 0, channels = 0;  // of the full image (level 0)
  bool linear = false;  // three channels that hold data, not sRGB colour (a normal map)
  std::span<const uint8_t> texels;  // every level: pyramid_bytes(width, height, channels)
  std::vector<uint8_t> owned;       // the texels, unless they live in a mapped scene image
  // Channel c at texture coordinates uv, bilinear and repeating, at level of detail `lod` (0: the full image;
  // between levels, trilinear); colour channels decoded from sRGB to linear (unless `linear`).
  float sample(Vec2 uv, uint32_t c, float lod = 0) const;
  // Channels 0, 1 and 2, each exactly as sample() gives it, for the cost of little more than one.
  RGB sample_rgb(Vec2 uv, float lod = 0) const;
  // Channel c of the full image's texel (x, y), repeating, decoded as sample() decodes it; y = 0 is the top row.
  float texel(int64_t x, int64_t y, uint32_t c) const;
  static uint64_t pyramid_bytes(uint32_t width, uint32_t height, uint32_t channels);
  // Fills `owned` beyond level 0 (which it must hold) with the smaller levels.
  void build_pyramid();
};

// What a triangle may carry beyond its corners: OBJ vertex normals and texture coordinates, per corner.
// A corner's tangent (glTF's TANGENT): the surface direction of increasing u, and the bitangent's side: the
// bitangent is sign * cross(normal, direction). A NaN direction: none (the frame then comes from the uvs).
struct CornerTangent {
  Vec3 direction;
  float sign = 1;
};

struct CornerAttributes {
  const Vec3* normals = nullptr;  // 3, or none
  const Vec2* uvs = nullptr;      // 3, or none
  const CornerTangent* tangents = nullptr;  // 3, or none
};

struct PointLight {
  Vec3 position;
  RGB intensity;  // W/sr per channel (a spot's on its axis)
  // A spot light (glTF's KHR_lights_punctual "spot"): it shines along `axis`, fully within cos_inner of it and
  // fading to nothing at cos_outer (glTF's smooth falloff, the square of the linear ramp). cos_outer < -1: every way.
  Vec3 axis{0, 0, -1};
  float cos_inner = 1, cos_outer = -2;
  bool spot() const { return cos_outer >= -1; }
  // The intensity towards unit direction d (from the light).
  RGB intensity_towards(Vec3 d) const {
    if (!spot()) return intensity;
    const float c = dot(d, axis);
    if (c <= cos_outer) return {};
    const float t = cos_inner > cos_outer ? std::min(1.0f, (c - cos_outer) / (cos_inner - cos_outer)) : 1.0f;
    return intensity * (t * t);
  }
  // Its flux, per channel's average: 4 pi I, or over a spot's outer cone (an upper bound, for light selection).
  double power() const {
    return spot() ? 2.0 * kPi * (1 - static_cast<double>(cos_outer)) * average(intensity) : 4.0 * kPi * average(intensity);
  }
};

struct ObjCatalogue {
  struct Texture {
    std::string material, slot, path;  // slot: the MTL statement (map_Kd, map_d, ...); path as found
    bool found = false;
  };
  std::vector<std::string> material_names;
  std::vector<Texture> textures;
  // A glTF file's perspective cameras, in node order: name (as the node or the camera names it) and view (at rest:
  // the nodes' own transforms). `animated`: an animation of the file moves its node or one of the node's ancestors,
  // its keys up to `animation_seconds` (Scene::gltf_camera_views gives the view at any time).
  struct FileCamera {
    std::string name;
    CameraSpec view;
    bool animated = false;
    double animation_seconds = 0;
  };
  std::vector<FileCamera> cameras;
  std::vector<std::string> warnings;
};

class Scene {
 public:
  Scene() = default;
  // Moving keeps the per-triangle views valid (a vector's move keeps its buffer); a copy would not, so none.
  Scene(Scene&&) = default;
  Scene& operator=(Scene&&) = default;
  Scene& operator=(const Scene&) = delete;

  uint32_t add_material(Material m);
  // Adds a planar quad a-b-c-d as two triangles; its front (emitting) side is the one (b-a)x(c-a) points to.
  void add_quad(Vec3 a, Vec3 b, Vec3 c, Vec3 d, uint32_t material);
  void add_triangle(Vec3 a, Vec3 b, Vec3 c, uint32_t material, CornerAttributes extra = {});
  uint32_t add_texture(Texture t);
  // For the binary forms: every triangle's corner normals, texture coordinates and tangents (3 each, or none)
  // exactly as stored, after the triangles.
  void restore_corners(std::vector<Vec3> normals, std::vector<Vec2> uvs, std::vector<CornerTangent> tangents = {});
  // A sphere as a subdivided icosahedron (20 * 4^subdivisions triangles), wound outwards.
  // An icosphere; `smooth`: with the sphere's own normals at the corners (shaded round, not faceted).
  void add_sphere(Vec3 center, float radius, int subdivisions, uint32_t material, bool smooth = false);
  void add_point_light(Vec3 position, RGB intensity) { point_lights_.push_back({position, intensity}); }
  void add_point_light(const PointLight& light) { point_lights_.push_back(light); }
  // Adds the lights a script declares (SceneSpec::lights); an error names what is wrong with one.
  // shape "name" { plane | sphere }: a script's geometry (SceneSpec::shapes), each with a material of its own
  // (named after the shape, grey until the script's material changes say otherwise) or one of the scene's.
  Status add_script_shapes(const Value::Array& shapes);
  Status add_script_lights(const Value::Array& lights);
  // Applies the script's changes to named materials (SceneSpec::materials): emission, kd, ks, ns, ior, type. An
  // unknown name, or kd + ks above 1 (a surface that creates energy), is an error naming the material.
  Status apply_material_overrides(const Value::Array& overrides);
  // The same changes to a list of materials (a frame's changes checked against the scene's, without a scene).
  // A frame's sun ({name = "sun", sun = {...}}), environment ({name = "environment", environment = {...}}) or point
  // light ({name = "bulb", light = {...}}) is not a material: left to apply_light_changes.
  static Status change_materials(std::vector<Material>& materials, const Value::Array& overrides);
  // A job frame's lights (frames { sun, environment, lights }): the scene's sun, declared by the script, moved or
  // changed as sun { } would give it; the environment's intensity and rotation (a map's) or radiance (a constant
  // one's), the map itself kept; a named point light of the script moved or its intensity changed. An error when the
  // scene has no sun, no environment or no such point light to change, or the change does not fit the environment's
  // kind; check_light_changes says so without changing anything.
  Status apply_light_changes(const Value::Array& changes);
  Status check_light_changes(const Value::Array& changes) const;
  // A job frame's material changes (frames { materials }) over this scene's materials: a scene that shares this one's
  // geometry and textures (its mapped image, or copies of its arrays), with the materials changed as
  // apply_material_overrides changes them and the lights settled again from them exactly as finalize() settles a
  // scene loaded with those changes (so frame k equals a farm whose script changes the materials as frame k does).
  // Geometry and cut-outs are this scene's: a BVH built over this scene serves the new one. `what` names the frame
  // in an error (a frame that leaves the scene without light).
  Result<std::shared_ptr<const Scene>> with_material_changes(const Value::Array& changes, const std::string& what) const;
  // Builds the light distribution. An error if the scene has no triangles or no light.
  Status finalize(const std::string& what);

  size_t triangle_count() const { return material_view_.size(); }
  std::span<const Vec3> vertices() const { return vertex_view_; }
  std::span<const std::array<uint32_t, 3>> triangles() const { return triangle_view_; }
  const Material& material(uint32_t id) const { return materials_[id]; }
  const std::vector<Material>& materials() const { return materials_; }
  uint32_t material_of(uint32_t triangle) const { return material_view_[triangle]; }
  Vec3 vertex(uint32_t triangle, int corner) const { return vertex_view_[triangle_view_[triangle][corner]]; }
  Vec3 normal(uint32_t triangle) const { return normal_view_[triangle]; }  // unit, from the winding
  float area(uint32_t triangle) const { return area_view_[triangle]; }
  // Surface detail at a point of a triangle, given by its barycentrics b (weights of corners 0, 1, 2; see
  // barycentrics()). Without vertex normals the shading normal is the geometric one; without a texture (or
  // texture coordinates) the albedo is the material's kd.
  Vec3 barycentrics(uint32_t triangle, Vec3 p) const;
  Vec3 shading_normal(uint32_t triangle, Vec3 b) const;  // unit, on the winding's side
  Vec2 uv(uint32_t triangle, Vec3 b) const;
  // `footprint`: how wide a pixel is at the point, in scene units (0: the texture's full resolution). The texture
  // is filtered to that width (its mip level), so a pixel's few samples see the mean colour it covers.
  RGB albedo(uint32_t triangle, Vec3 b, float footprint = 0) const;
  // The radiance emitter triangle t emits at barycentrics b (its material's ke, times its emission map there).
  RGB emission(uint32_t triangle, Vec3 b) const {
    const Material& m = material(material_of(triangle));
    return m.emission_map < 0 || !has_uvs() ? m.ke : mapped_emission(triangle, b);
  }
  // The same at point p on the triangle (its barycentrics found only where a map needs them).
  RGB emission_at(uint32_t triangle, Vec3 p) const {
    const Material& m = material(material_of(triangle));
    return m.emission_map < 0 || !has_uvs() ? m.ke : mapped_emission(triangle, barycentrics(triangle, p));
  }
  // Its mean over the material's emission map (ke without one): what light selection and radiosity take.
  RGB mean_emission(const Material& m) const;
  // Whether any triangle's material has a normal map (surface_at then looks).
  bool has_normal_maps() const { return has_normal_maps_; }
  // Shading normal n (unit, on the winding's side) at barycentrics b of a triangle whose material has a normal map,
  // turned as the map says in the tangent frame there: the file's tangents where it gave them (glTF's TANGENT),
  // else the triangle's from its texture coordinates (x along u, y along v).
  Vec3 normal_mapped(uint32_t triangle, Vec3 b, Vec3 n) const;
  // The file's tangent frame at barycentrics b around unit normal n; false without usable tangents there.
  bool file_tangent_frame(uint32_t triangle, Vec3 b, Vec3 n, Vec3& tangent, Vec3& bitangent) const;
  // A metal_rough material's metallic and roughness at barycentrics b: its factors, times its maps' values there.
  void metal_rough_at(uint32_t triangle, Vec3 b, float footprint, float& metallic, float& roughness) const;
  // Whether the surface is there at barycentrics b (false where an alpha map cuts it out).
  bool opaque(uint32_t triangle, Vec3 b) const;
  // Whether opaque() holds at every point of the triangle: no alpha map, or every texel its bilinear lookups can
  // reach is well above the cut. Conservative (false when unsure, e.g. a footprint of more than 4096 texels), so
  // the tracer can leave such triangles unfiltered without changing any hit.
  bool opaque_everywhere(uint32_t triangle) const;
  // Whether any material is cut out by an alpha map (the tracer then filters its hits).
  bool has_cutouts() const;
  // Reorders `triangles` so that those opaque everywhere come first, each group in its former order; returns how
  // many are. The tracer builds each group as an Embree geometry of its own (only the rest need the alpha filter).
  size_t put_opaque_first(std::vector<uint32_t>& triangles) const;
  // Every triangle of a scene with cut-outs, put_opaque_first's order (`opaque` of them first), and their corners
  // in that order: what the tracer's two geometries are made of. Only a mapped scene has it (in its image, so the
  // actors of a host share it as they share the rest); else empty, and each tracer makes its own.
  struct OpaqueFirst {
    std::span<const uint32_t> triangles;
    std::span<const std::array<uint32_t, 3>> corners;
    size_t opaque = 0;
  };
  const OpaqueFirst& opaque_first() const { return opaque_first_; }
  // The share of a triangle's area that is not cut out (1 without an alpha map), from a fixed grid of points.
  float opaque_fraction(uint32_t triangle) const;
  // Emitted flux of emitter triangle t: pi * area * mean(Le) * opaque_fraction.
  float emitted_power(uint32_t triangle) const;
  bool has_shading_normals() const { return !corner_normal_view_.empty(); }
  Vec3 corner_normal(uint32_t triangle, int corner) const { return corner_normal_view_[3 * size_t{triangle} + corner]; }
  Vec2 corner_uv(uint32_t triangle, int corner) const { return corner_uv_view_[3 * size_t{triangle} + corner]; }
  bool has_uvs() const { return !corner_uv_view_.empty(); }
  bool has_tangents() const { return !corner_tangent_view_.empty(); }
  CornerTangent corner_tangent(uint32_t triangle, int corner) const { return corner_tangent_view_[3 * size_t{triangle} + corner]; }
  const std::vector<Texture>& textures() const { return textures_; }

  // True when the per-triangle arrays live in a memory-mapped scene image that other processes on this host
  // share (render/scene/scene_image.hpp); the vertex array is then padded for Embree's 16-byte loads.
  bool shares_storage() const { return storage_ != nullptr; }

  // Lights: emitter triangles, then point lights, chosen with probability proportional to emitted flux.
  const std::vector<uint32_t>& emitters() const { return emitters_; }
  const std::vector<PointLight>& point_lights() const { return point_lights_; }
  // The light at infinity (render/lights/environment.hpp): an environment map or radiance and a sun; null without.
  // Set before finalize().
  void set_environment(Environment env) { environment_ = std::make_shared<const Environment>(std::move(env)); }
  const Environment* environment() const { return environment_.get(); }
  // The share of light samples that go to the environment rather than to the other lights: all of them when it is
  // the only light, else half (as pbrt-v4's light sampler gives its infinite lights: the tree's choice depends on
  // the point, the environment's reach does not, and neither can be weighed against the other from the point
  // alone). 0 without one.
  float environment_share() const { return environment_share_; }
  // What a camera ray that leaves the scene in direction `d` sees.
  RGB background(Vec3 d) const {
    return environment_ && environment_->camera_visible() ? environment_->radiance(d) : RGB{};
  }
  // Picks a light for u in [0,1); an index below emitters().size() is a triangle, above it a point light.
  // With `remainder`: where u fell within that light's share of [0, 1), rescaled to [0, 1) (LightTree::pick).
  size_t pick_emitter(float u, float& probability, float* remainder = nullptr) const;
  // Probability that pick_emitter chooses triangle t (0 for non-emitters).
  float emitter_probability_of_triangle(uint32_t t) const { return light_pdf_view_[t]; }
  // The lights by what each can give a point (render/lights/light_tree.hpp), in the same numbering (after finalize()).
  const LightTree& light_tree() const { return *light_tree_; }
  // Where light samples on cut-out emitters are drawn (render/lights/emitter_cutouts.hpp).
  const EmitterCutouts& emitter_cutouts() const { return *emitter_cutouts_; }
  // The index of emitter triangle t in emitters() (t must be an emitter).
  size_t emitter_index_of(uint32_t t) const;

  // The box around every vertex (after finalize()).
  const Bounds& bounds() const { return bounds_; }
  // A distance small against the scene's size: the ray offset for points that name no triangle, and a scale for
  // tolerances that are not about floating-point error (a photon map's default radius, radiosity's gather).
  float epsilon() const { return epsilon_; }
  // Where a ray that leaves point p of `triangle` on the side of unit normal `side` (the face's normal, or its
  // opposite for a ray through the face) starts: kRayOffsetUlps units of float precision of the coordinates
  // involved above the face's plane. The height is measured from the plane itself, so the origin is on the right
  // side whatever rounding p carries (a point found as origin + t * direction is off the plane by that ray's
  // error), and it scales with the coordinates, not with the scene, so small things in a large scene are not
  // pushed apart. `triangle` = UINT32_MAX (a point that names none): p + side * epsilon().
  Vec3 ray_origin(uint32_t triangle, Vec3 p, Vec3 side) const {
    if (triangle == UINT32_MAX) return p + side * epsilon_;
    const Vec3 a = vertex(triangle, 0);
    const float scale = std::max(largest_coordinate(p), largest_coordinate(a));
    // p's distance from the plane, off by about one unit of scale's precision: well inside the margin.
    const float height = dot(side, p - a);
    return p + side * (kRayOffsetUlps * std::numeric_limits<float>::epsilon() * scale - height);
  }
  // Where a ray in direction d (unit, on `side`'s side) from p starts: on the line from p itself, at the height
  // ray_origin() gives. A ray from straight above p sees the world from up there: 5000 units out, where that height
  // is 0.076, a light 1 above a floor looked brighter to BSDF rays than to light samples (whose shadow rays only ask
  // whether the way is clear), and MIS read the floor up to 2.4 % bright. Directions within 4 degrees of the face,
  // which would reach that height far along, start at ray_origin() instead.
  Vec3 ray_origin_along(uint32_t triangle, Vec3 p, Vec3 side, Vec3 d) const {
    const float c = dot(side, d);
    if (triangle == UINT32_MAX || !(c > 1.0f / 16)) return ray_origin(triangle, p, side);
    const Vec3 a = vertex(triangle, 0);
    const float scale = std::max(largest_coordinate(p), largest_coordinate(a));
    const float height = dot(side, p - a);
    return p + d * ((kRayOffsetUlps * std::numeric_limits<float>::epsilon() * scale - height) / c);
  }
  // Embree's float test of an origin against a triangle is off by a few units of the precision of the coordinates
  // involved (differences of coordinates, the face normal from a cross product, which thin triangles make less
  // precise); 128 leaves a wide margin and is still 1e-5 of them.
  static constexpr float kRayOffsetUlps = 128;

  static Result<Scene> builtin(const std::string& name);
  static Result<Scene> load_obj(const std::string& path);
  // Without finalize(), so that script lights can still be added.
  static Result<Scene> builtin_unlit(const std::string& name);
  static Result<Scene> load_obj_unlit(const std::string& path);
  // The same from an OBJ's and its MTL's text, without textures; `label` names it in messages (the OBJ fuzzer).
  static Result<Scene> parse_obj_unlit(const std::string& obj_text, const std::string& mtl_text,
                                       const std::string& label);
  static Result<Scene> load(const SceneSpec& spec);
  // What an OBJ file's text says apart from its geometry: its libraries' material names (for script checks) and
  // warnings naming file and line (a missing library, a usemtl of an unknown material). Reads no geometry.
  static Result<ObjCatalogue> catalogue_obj(const std::string& path);
  static const std::vector<std::string>& builtin_names();
  // glTF 2.0 (.gltf, .glb; render/scene/gltf_scene.cpp): the default scene, without finalize(); its catalogue (the
  // materials' names as the scene gives them, tinygltf's warnings). An OBJ otherwise.
  static bool is_gltf_path(const std::string& path);
  static Result<Scene> load_gltf_unlit(const std::string& path);
  // The same from a file's bytes in memory (the glTF fuzzer); `path` names it in messages.
  static Result<Scene> parse_gltf_unlit(const std::string& path, const std::string* bytes);
  // `bytes`: the file's content, parsed from memory (the fuzz target), instead of reading `path`.
  static Result<ObjCatalogue> catalogue_gltf(const std::string& path, const std::string* bytes = nullptr);
  // The view of the file's camera `index` (in catalogue order) at each of `seconds` of the file's animations, which
  // play together as glTF players play them: translation, rotation and scale channels of the camera's node and its
  // ancestors, with their STEP, LINEAR (rotations: shortest slerp) or CUBICSPLINE interpolation, held before the
  // first key and after the last. An error names what in the file cannot be read.
  static Result<std::vector<CameraSpec>> gltf_camera_views(const std::string& path, size_t index,
                                                           const std::vector<double>& seconds,
                                                           const std::string* bytes = nullptr);
  // A scene file of either kind, by its extension.
  static Result<Scene> load_file_unlit(const std::string& path) {
    return is_gltf_path(path) ? load_gltf_unlit(path) : load_obj_unlit(path);
  }
  static Result<ObjCatalogue> catalogue_file(const std::string& path) {
    return is_gltf_path(path) ? catalogue_gltf(path) : catalogue_obj(path);
  }

 private:
  friend class SceneImage;
  // Copies are made on purpose only (with_material_changes): a scene can weigh gigabytes.
  Scene(const Scene&) = default;
  // What tinyobjloader read, as one of our scenes; `path` names it in messages, textures are read from
  // `texture_dir` (none when it is empty).
  static Result<Scene> from_obj_reader(const tinyobj::ObjReader& reader, const std::string& path,
                                       const std::string& texture_dir);
  // Points the per-triangle views at the vectors below (a scene being built, or loaded the ordinary way).
  void view_owned_arrays();
  // The lights from the materials (finalize()'s second half): emitters, their choice by flux, the light tree.
  Status settle_lights(const std::string& what);

  // Per-triangle arrays while building; a mapped scene leaves them empty and views its image instead.
  std::vector<Vec3> vertices_;
  std::vector<std::array<uint32_t, 3>> triangles_;
  std::vector<uint32_t> material_of_;
  std::vector<Vec3> normals_;
  std::vector<float> areas_;
  std::vector<Vec3> corner_normals_;  // 3 per triangle, or none
  std::vector<Vec2> corner_uvs_;      // 3 per triangle, or none
  std::vector<CornerTangent> corner_tangents_;  // 3 per triangle, or none
  std::vector<Texture> textures_;
  std::vector<Material> materials_;
  std::vector<uint32_t> emitters_;
  std::vector<PointLight> point_lights_;
  std::vector<float> emitter_cdf_;
  std::vector<float> emitter_pdf_;
  std::vector<float> triangle_light_pdf_;
  std::span<const Vec3> vertex_view_;
  std::span<const std::array<uint32_t, 3>> triangle_view_;
  std::span<const uint32_t> material_view_;
  std::span<const Vec3> normal_view_;
  std::span<const float> area_view_;
  std::span<const float> light_pdf_view_;
  std::span<const Vec3> corner_normal_view_;
  std::span<const Vec2> corner_uv_view_;
  std::span<const CornerTangent> corner_tangent_view_;
  std::shared_ptr<const LightTree> light_tree_;
  std::shared_ptr<const EmitterCutouts> emitter_cutouts_;
  std::shared_ptr<const Environment> environment_;
  float environment_share_ = 0;
  void settle_environment_share();
  bool has_normal_maps_ = false;
  void settle_normal_maps();
  RGB mapped_emission(uint32_t triangle, Vec3 b) const;
  std::shared_ptr<const void> storage_;  // the mapping the views point into, when mapped
  OpaqueFirst opaque_first_;             // views into the mapping, when mapped
  std::vector<std::string> ambient_only_;  // OBJ materials with Ka but no Ke: named if the scene ends up unlit
  Bounds bounds_;
  float epsilon_ = 1e-4f;
};

}  // namespace lf
