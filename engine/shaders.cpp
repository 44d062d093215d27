// The GLSL sources of the renderer's programs (engine/shaders.h names them) and buildProgram.
// Every fragment shader is compiled after kCommonFS; what each program draws: docs/RENDERING.md.
//
// Index of this file:
// [SECTION] Common fragment code: lights, shadows, tone mapping, the radiance's two parts
// [SECTION] Meshes and hulls (spheres, capsules)
// [SECTION] Hair
// [SECTION] The ground, the deferred shading, the upsampled ground, the background, the ground's shadow
// [SECTION] Post-process anti-aliasing
// [SECTION] The full-screen triangle
// [SECTION] Debug lines, depth only
// [SECTION] Compiling and linking

#include "engine/shaders.h"

#include <glad/gl.h>

#include <algorithm>
#include <vector>

namespace ponyhop::shaders {

// ---------------------------------------------------------------------------------------------
// [SECTION] Common fragment code: lights, shadows, tone mapping, the radiance's two parts
// Shared by the lit and ground fragment shaders: lights, shadow lookup, tone mapping, sRGB, the
// background gradient (so that the ground can fade into exactly the colour behind it).
static const char* const kCommonFS = R"GLSL(
uniform vec3 u_eye;
uniform vec3 u_lightDir;       // unit, the direction the key light travels
uniform vec3 u_lightColor;     // linear rgb * intensity
uniform vec3 u_fillDir;        // unit, direction the fill light travels (from the camera side)
uniform vec3 u_fillColor;      // linear rgb * fill
uniform vec3 u_skyAmbient;     // linear, hemispheric ambient from above
uniform vec3 u_groundAmbient;  // linear, bounce from below
uniform float u_exposure;
uniform mat4 u_lightViewProj;
uniform sampler2DShadow u_shadowMap;
uniform float u_shadowTexel;     // 1 / shadow map size
uniform float u_shadowSoftness;  // PCF radius, texels
uniform float u_normalOffset;    // m, receiver offset along the normal (about 1.5 texels)
uniform int u_shadowsOn;
uniform int u_shadowDraft;       // 1: plain PCF (draft quality), 0: soft shadows with contact hardening
uniform sampler2D u_shadowDepth;       // the same depth texture, raw depths (blocker search)
uniform float u_lightDepthRange;       // m per unit of shadow-map depth
uniform float u_texelWorld;            // m per shadow texel
uniform float u_penumbraSlope;         // tan(angular radius of the key light)
uniform float u_maxPenumbraTexels;     // cap of the penumbra radius (and the blocker search)
uniform vec3 u_bgTop;            // sRGB, display values
uniform vec3 u_bgBottom;
uniform vec2 u_viewport;

vec3 srgbToLinear(vec3 c) {
  return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(0.04045, c));
}
vec3 linearToSrgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
// linearToSrgb() (the ground's, and the deferred shading's: kDeferredFS and the LIT_COLOR output) from
// three square roots: a fit of 1.055 c^(1/2.4) - 0.055 on [0.0031308, 1] in c, c^(1/2), c^(1/4),
// c^(1/8), within 0.012 of one 8-bit step everywhere. llvmpipe computes pow() as a log and an exp
// per channel: on the hopper at 1280x720 the deferred passes took about 0.3 ms less with this.
vec3 linearToSrgbFast(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  vec3 s1 = sqrt(c), s2 = sqrt(s1), s3 = sqrt(s2);
  vec3 g = -0.01756295 * c + 0.64236556 * s1 + 0.71211042 * s2 - 0.3368699 * s3;
  return mix(c * 12.92, g, step(0.0031308, c));
}
// Filmic curve (Narkowicz's fit of ACES): keeps the key light's highlights from clipping.
vec3 toneMap(vec3 x) {
  x *= u_exposure;
  return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}
vec3 background(float y) {  // y: 0 bottom .. 1 top of the viewport; display (sRGB) values
  float t = smoothstep(0.0, 1.0, clamp(y, 0.0, 1.0));
  return mix(u_bgBottom, u_bgTop, t);
}

// 12-tap Poisson disk (unit radius); each tap is a hardware 2x2 bilinear depth compare, so the
// penumbra is smooth even for small radii. Fixed pattern: deterministic, no noise.
const vec2 kPoisson[12] = vec2[](
  vec2(-0.326, -0.406), vec2(-0.840, -0.074), vec2(-0.696, 0.457), vec2(-0.203, 0.621),
  vec2(0.962, -0.195), vec2(0.473, -0.480), vec2(0.519, 0.767), vec2(0.185, -0.893),
  vec2(0.507, 0.064), vec2(0.896, 0.412), vec2(-0.322, -0.933), vec2(-0.792, -0.598));

// Soft shadows with contact hardening (percentage-closer soft shadows, Fernando 2005, for a
// directional light of angular radius theta): 1) blocker search: the mean depth d_b of the
// occluders around the lookup; 2) penumbra radius w = (d_r - d_b) * tan(theta) in metres, at
// least `shadow_softness` texels; 3) PCF over that radius. Shadows are crisp where an object
// touches the ground and widen with the distance to the caster, like a real sky-lit sun.
// The lookup point of a receiver at P with normal N: shadow-map xy and depth. Normal offset: the
// lookup moves off the surface by ~1.5 texels, more at grazing light, so a lit surface never
// compares against its own depth (acne) while contact stays tight.
vec3 shadowCoord(vec3 P, vec3 N) {
  float ndl = clamp(dot(N, -u_lightDir), 0.0, 1.0);
  vec3 Po = P + N * u_normalOffset * (0.5 + (1.0 - ndl));
  vec4 s = u_lightViewProj * vec4(Po, 1.0);
  return s.xyz / s.w * 0.5 + 0.5;
}
bool outsideShadowMap(vec3 c) { return c.x <= 0.0 || c.x >= 1.0 || c.y <= 0.0 || c.y >= 1.0 || c.z >= 1.0; }

// 1) Blockers within the largest penumbra we allow: how many of the 7 taps (x) and their depths'
// sum (y). A tap blocks when its depth is nearer the light than the receiver's plane there, less
// `eps`: the plane through c with depth slope g (per unit of shadow-map xy); the plain search
// takes the flat plane at c.z (g = 0, eps = 0: exactly the comparison d < c.z).
vec2 shadowBlockers(vec3 c, vec2 g, float eps) {
  float searchR = u_maxPenumbraTexels * u_shadowTexel;
  float sumB = 0.0, nB = 0.0;
  for (int i = 0; i < 12; i += 2) {  // 6 of the 12 directions + the centre: cheap, and enough
    vec2 o = kPoisson[i] * searchR;
    float d = texture(u_shadowDepth, c.xy + o).r;
    if (d < c.z + dot(g, o) - eps) { sumB += d; nB += 1.0; }
  }
  float dCentre = texture(u_shadowDepth, c.xy).r;
  if (dCentre < c.z - eps) { sumB += dCentre; nB += 1.0; }
  return vec2(nB, sumB);
}
vec2 shadowBlockers(vec3 c) { return shadowBlockers(c, vec2(0.0), 0.0); }

float shadowFactor(vec3 P, vec3 N) {
  if (u_shadowsOn == 0) return 1.0;
  vec3 c = shadowCoord(P, N);
  if (outsideShadowMap(c)) return 1.0;
  if (u_shadowDraft != 0) {  // draft quality: 5 bilinear compares over the minimum radius
    float rd = max(u_shadowSoftness, 1.0) * u_shadowTexel;
    return 0.2 * (texture(u_shadowMap, c) + texture(u_shadowMap, vec3(c.xy + vec2(rd, rd), c.z)) +
                  texture(u_shadowMap, vec3(c.xy + vec2(-rd, rd), c.z)) +
                  texture(u_shadowMap, vec3(c.xy + vec2(rd, -rd), c.z)) +
                  texture(u_shadowMap, vec3(c.xy - vec2(rd, rd), c.z)));
  }
  vec2 b = shadowBlockers(c);
  float nB = b.x;
  if (nB == 0.0) return 1.0;  // nothing between this point and the light: fully lit, no PCF
  if (nB == 7.0) return 0.0;  // blockers all over the widest penumbra: deep in the umbra, no PCF
  // 2) Penumbra (depths are linear for an orthographic light: metres = depth * range).
  float dBlocker = b.y / nB;
  float wTexels = (c.z - dBlocker) * u_lightDepthRange * u_penumbraSlope / u_texelWorld;
  float r = clamp(max(u_shadowSoftness, wTexels), 0.0, u_maxPenumbraTexels) * u_shadowTexel;
  // 3) PCF: each tap is a hardware 2x2 bilinear depth compare.
  float sum = texture(u_shadowMap, c);
  for (int i = 0; i < 12; ++i) sum += texture(u_shadowMap, vec3(c.xy + kPoisson[i] * r, c.z));
  for (int i = 0; i < 12; i += 3) sum += texture(u_shadowMap, vec3(c.xy - kPoisson[i].yx * (0.5 * r), c.z));
  return sum / 17.0;
}

// What shadowFactor() knows before its filter: 1 fully lit, 0 deep in the umbra, 0.5 when the
// filter is needed (always in draft). llvmpipe runs both sides of every branch, so the early
// returns above save nothing per fragment; the ground's shadow texture instead runs this first
// and the whole of shadowFactor() only where it says 0.5, selected by the depth test.
float shadowClass(vec3 P, vec3 N) {
  if (u_shadowsOn == 0) return 1.0;
  vec3 c = shadowCoord(P, N);
  if (outsideShadowMap(c)) return 1.0;
  if (u_shadowDraft != 0) return 0.5;
  float nB = shadowBlockers(c).x;
  return nB == 0.0 ? 1.0 : (nB == 7.0 ? 0.0 : 0.5);
}

// What the deferred shading's first pass (kDeferredFS) knows of shadowFactor(P, N) before its
// filter: 1 when nothing can shadow the receiver at P (normal N), 0 deep in the umbra, 0.5 when
// the whole filter must decide. Nothing above: no shadow-map texel within the blocker search's
// reach rises above the receiver's tangent plane (through the lookup point), so shadowFactor() is
// 1 up to its own filter's self-shadowing on slopes. The plain search counts the receiver's own
// surface uphill of the lookup as blockers on every slope and curve (and so runs the filter
// there); measured against the tangent plane, a flat or convex lit surface has none. Errors
// (sampling the nearest texel, a plane seen edge-on from the light) only ever add blockers: such
// a point takes the whole shadowFactor(). The umbra: the same taps compared with the flat plane
// at the lookup's depth, as shadowFactor()'s own blocker search does, all blocked, where
// shadowFactor() returns 0 before its filter (not in draft, which filters everywhere).
float shadowKnown(vec3 P, vec3 N) {
  vec3 c = shadowCoord(P, N);
  if (outsideShadowMap(c)) return 1.0;
  // The tangent plane's depth as an affine function of the shadow-map xy: depth = c.z + g . dxy.
  vec3 t1 = normalize(cross(N, abs(N.z) < 0.9 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0)));
  vec3 t2 = cross(N, t1);
  vec3 a = 0.5 * (u_lightViewProj * vec4(t1, 0.0)).xyz, b = 0.5 * (u_lightViewProj * vec4(t2, 0.0)).xyz;
  float det = a.x * b.y - a.y * b.x;
  // Edge-on (or nearly): the plane's depth is undefined in xy; only the umbra can be known.
  bool edgeOn = abs(det) < 1e-6 * (dot(a, a) + dot(b, b));
  vec2 g = edgeOn ? vec2(0.0) : vec2(a.z * b.y - a.y * b.z, a.x * b.z - a.z * b.x) / det;
  // The blocker search's own taps (shadowBlockers()), against the plane with a quarter texel of
  // depth to spare, and against the flat plane as shadowFactor() compares them.
  float eps = 0.25 * u_texelWorld / u_lightDepthRange;
  float searchR = u_maxPenumbraTexels * u_shadowTexel;
  float nPlane = 0.0, nFlat = 0.0;
  for (int i = 0; i < 12; i += 2) {
    vec2 o = kPoisson[i] * searchR;
    float d = texture(u_shadowDepth, c.xy + o).r;
    if (d < c.z + dot(g, o) - eps) nPlane += 1.0;
    if (d < c.z) nFlat += 1.0;
  }
  float dCentre = texture(u_shadowDepth, c.xy).r;
  if (dCentre < c.z - eps) nPlane += 1.0;
  if (dCentre < c.z) nFlat += 1.0;
  if (!edgeOn && nPlane == 0.0) return 1.0;
  return (u_shadowDraft == 0 && nFlat == 7.0) ? 0.0 : 0.5;
}

// Linear radiance of a surface point (before tone mapping), in two parts: `key`, the key light's
// share before its shadow, and `rest` (fill, ambient, the rim's sky part). The radiance is
// key * shadowFactor(P, N) + rest: emit() below, or the deferred shading pass (kDeferredFS).
void shadeTerms(vec3 P, vec3 N, vec3 albedo, float specular, float shininess, float rim, out vec3 key,
                out vec3 rest) {
  vec3 V = normalize(u_eye - P);
  vec3 L = -u_lightDir;
  float ndl = max(dot(N, L), 0.0);
  vec3 H = normalize(L + V);
  // Normalized Blinn-Phong: (n + 8) / 8 keeps highlight energy steady as shininess changes.
  float spec = specular * (shininess + 8.0) / 8.0 * pow(max(dot(N, H), 0.0), shininess) * ndl;
  // Rim: a thin sky-coloured edge that separates the object from the background.
  float fr = pow(1.0 - max(dot(N, V), 0.0), 4.0);
  // A face turned away from the key light gets none of it, shadow or not.
  key = u_lightColor * (albedo * ndl + vec3(spec) + 0.5 * rim * fr) * step(1e-30, ndl);
  float fdl = max(dot(N, -u_fillDir), 0.0);
  vec3 fill = u_fillColor * albedo * fdl;
  vec3 amb = albedo * mix(u_groundAmbient, u_skyAmbient, 0.5 + 0.5 * N.z);
  rest = fill + amb + rim * fr * u_skyAmbient * 2.0;
}

// Kajiya-Kay hair with two shifted lobes (Scheuermann's practical take on Marschner's R and TRT),
// the two parts of the radiance as shadeTerms() gives them, for hair along the unit tangent T with
// the (clump's or scalp's) normal N, linear colour `color`, ambient occlusion `occlusion` and
// `shading` = (highlight strength, shift): diffuse follows sin(T, L), softened by how much the
// surface faces the light (wrapped N.L, so the far side is darker); the primary highlight is white
// with its tangent shifted one way, the secondary is tinted by the hair colour, broader, shifted
// the other way. Used by the strands (kHairFS) and a head's hair region (kMeshMatFS, SCALP_HAIR).
float strandSpec(vec3 T, vec3 H, float e) {
  float th = dot(T, H);
  return pow(sqrt(max(1.0 - th * th, 0.0)), e);
}
void strandTerms(vec3 P, vec3 T, vec3 N, vec3 color, float occlusion, vec2 shading, out vec3 key, out vec3 rest) {
  vec3 V = normalize(u_eye - P);
  vec3 L = -u_lightDir;
  float tl = dot(T, L);
  float kk = sqrt(max(1.0 - tl * tl, 0.0));
  float wrap = clamp((dot(N, L) + 0.6) / 1.6, 0.0, 1.0);
  vec3 H = normalize(L + V);
  float shift = shading.y;
  vec3 T1 = normalize(T + shift * N);
  vec3 T2 = normalize(T - 1.5 * shift * N);
  float spec = shading.x * (strandSpec(T1, H, 90.0) * 1.4);
  vec3 spec2 = shading.x * 0.8 * color * 4.0 * strandSpec(T2, H, 24.0);
  key = u_lightColor * (wrap * occlusion) * (color * kk * 0.85 + vec3(spec) + spec2);
  float fdl = clamp((dot(N, -u_fillDir) + 0.5) / 1.5, 0.0, 1.0);
  vec3 fill = u_fillColor * color * fdl * occlusion;
  vec3 amb = color * mix(u_groundAmbient, u_skyAmbient, 0.5 + 0.5 * N.z) * occlusion;
  rest = fill + amb;
}
)GLSL";

// The end of the lit fragment shaders (kLitFS, kMeshMatFS, kHairFS), given the point and the normal
// shadowFactor() is to see and the two parts of the radiance (shadeTerms()). Forward: the shadow is
// looked up here and the pixel finished. With SPLIT_LIGHT (single-sample frames with shadows):
// the fragment only writes what the deferred shading pass (kDeferredFS) needs, and that pass
// searches the shadow map once per visible pixel: llvmpipe shades whole blocks of pixels per
// triangle, so on a mesh of small triangles a search per fragment would run several times per
// pixel. The position is kept in full float (the search sees the exact point), the normal in
// octahedral form, 12 bits a coordinate, packed into one exactly representable float (within
// 1e-3 rad: it only sets the normal offset of the lookup).
#define PONYHOP_EMIT                                                                 \
  "#ifdef SPLIT_LIGHT\n"                                                             \
  "layout(location = 0) out vec4 o_surface;\n"                                       \
  "layout(location = 1) out vec4 o_key;\n"                                           \
  "layout(location = 2) out vec4 o_rest;\n"                                          \
  "layout(location = 3) out vec4 o_lit;\n"                                           \
  "float packNormal(vec3 n) {\n"                                                     \
  "  n /= abs(n.x) + abs(n.y) + abs(n.z);\n"                                         \
  "  vec2 s = vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);\n"             \
  "  vec2 p = n.z >= 0.0 ? n.xy : (1.0 - abs(n.yx)) * s;\n"                          \
  "  vec2 q = floor((p * 0.5 + 0.5) * 4095.0 + 0.5);\n"                              \
  "  return q.x + q.y * 4096.0;\n"                                                   \
  "}\n"                                                                              \
  "void emit(vec3 P, vec3 N, vec3 key, vec3 rest) {\n"                               \
  "  o_surface = vec4(P, packNormal(N));\n"                                          \
  "  o_key = vec4(key, 1.0);\n"                                                      \
  "  o_rest = vec4(rest, 1.0);\n"                                                    \
  "#ifdef LIT_COLOR\n"                                                               \
  "  o_lit = vec4(linearToSrgbFast(toneMap(key + rest)), 1.0);\n"                    \
  "#else\n"                                                                          \
  "  o_lit = vec4(0.0);\n"                                                           \
  "#endif\n"                                                                         \
  "}\n"                                                                              \
  "#else\n"                                                                          \
  "out vec4 o_color;\n"                                                              \
  "void emit(vec3 P, vec3 N, vec3 key, vec3 rest) {\n"                               \
  "  o_color = vec4(linearToSrgb(toneMap(key * shadowFactor(P, N) + rest)), 1.0);\n" \
  "}\n"                                                                              \
  "#endif\n"

// ---------------------------------------------------------------------------------------------
// [SECTION] Meshes and hulls (spheres, capsules)
const char* const kMeshVS = R"GLSL(
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_viewProj;
uniform mat4 u_model;
uniform mat3 u_normalMat;   // inverse transpose of the model's 3x3
uniform vec4 u_colorSpec;   // linear albedo, specular
uniform vec2 u_shinRim;     // shininess, rim
uniform vec4 u_clipPlane;   // gl_ClipDistance[0] (enabled over the half-resolution ground)
out vec3 v_pos;
out vec3 v_normal;
flat out vec4 v_colorSpec;
flat out vec2 v_shinRim;
void main() {
  vec4 w = u_model * vec4(a_pos, 1.0);
  v_pos = w.xyz;
  v_normal = u_normalMat * a_normal;
  v_colorSpec = u_colorSpec;
  v_shinRim = u_shinRim;
  gl_ClipDistance[0] = dot(u_clipPlane, w);
  gl_Position = u_viewProj * w;
}
)GLSL";

// A mesh with its file's materials: vertex colours (linear, base colour included) and texture
// coordinates for its base-colour texture.
const char* const kMeshMatVS = R"GLSL(
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;
layout(location = 3) in vec2 a_uv;
uniform mat4 u_viewProj;
uniform mat4 u_model;
uniform mat3 u_normalMat;
uniform vec4 u_colorSpec;
uniform vec2 u_shinRim;
uniform vec4 u_clipPlane;
out vec3 v_pos;
out vec3 v_normal;
out vec4 v_color;
out vec2 v_uv;
flat out vec4 v_colorSpec;
flat out vec2 v_shinRim;
void main() {
  vec4 w = u_model * vec4(a_pos, 1.0);
  v_pos = w.xyz;
  v_normal = u_normalMat * a_normal;
  v_color = a_color;
  v_uv = a_uv;
  v_colorSpec = u_colorSpec;
  v_shinRim = u_shinRim;
  gl_ClipDistance[0] = dot(u_clipPlane, w);
  gl_Position = u_viewProj * w;
}
)GLSL";

// The convex hull of two spheres (p0, r0) and (p1, r1) from one static mesh. Each vertex holds an
// azimuth (cos, sin), a parameter t in 0..1 along its cap and the cap it belongs to. The hull's
// side is a cone tangent to both spheres; its normal makes the angle alpha = asin((r0 - r1) / L)
// with the equator, so cap 0 covers elevations -90..alpha of sphere 0, cap 1 covers alpha..90 of
// sphere 1, and the band between the two last rings is the cone (same normal at both ends: smooth).
// Spheres (L = 0) and plain capsules (r0 = r1) are special cases. Two segments sharing an end
// point and radius both contain that whole sphere, so chains have no gaps.
const char* const kCapsuleVS = R"GLSL(
layout(location = 0) in vec4 a_param;     // cos(az), sin(az), t, cap (0 or 1)
layout(location = 1) in vec4 i_p0r0;
layout(location = 2) in vec4 i_p1r1;
layout(location = 3) in vec4 i_colorSpec; // linear albedo, specular
layout(location = 4) in vec2 i_shinRim;
uniform mat4 u_viewProj;
uniform vec4 u_clipPlane;
out vec3 v_pos;
out vec3 v_normal;
flat out vec4 v_colorSpec;
flat out vec2 v_shinRim;
const float HALF_PI = 1.5707963;
void main() {
  vec3 p0 = i_p0r0.xyz, p1 = i_p1r1.xyz;
  float r0 = i_p0r0.w, r1 = i_p1r1.w;
  vec3 d = p1 - p0;
  float len = length(d);
  vec3 w = len > 1e-7 ? d / len : vec3(0.0, 0.0, 1.0);
  vec3 helper = abs(w.z) < 0.9 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
  vec3 u = normalize(cross(helper, w));
  vec3 v = cross(w, u);
  float alpha = len > 1e-7 ? asin(clamp((r0 - r1) / len, -1.0, 1.0)) : 0.0;
  bool cap1 = a_param.w > 0.5;
  float e = cap1 ? mix(alpha, HALF_PI, a_param.z) : mix(-HALF_PI, alpha, a_param.z);
  vec3 n = cos(e) * (a_param.x * u + a_param.y * v) + sin(e) * w;
  v_pos = (cap1 ? p1 : p0) + (cap1 ? r1 : r0) * n;
  v_normal = n;
  v_colorSpec = i_colorSpec;
  v_shinRim = i_shinRim;
  gl_ClipDistance[0] = dot(u_clipPlane, vec4(v_pos, 1.0));
  gl_Position = u_viewProj * vec4(v_pos, 1.0);
}
)GLSL";

const char* const kLitFS = PONYHOP_EMIT R"GLSL(
in vec3 v_pos;
in vec3 v_normal;
flat in vec4 v_colorSpec;
flat in vec2 v_shinRim;
void main() {
  vec3 N = normalize(v_normal);
  if (!gl_FrontFacing) N = -N;  // open or inside-out meshes still light correctly
  vec3 key, rest;
  shadeTerms(v_pos, N, v_colorSpec.rgb, v_colorSpec.a, v_shinRim.x, v_shinRim.y, key, rest);
  emit(v_pos, N, key, rest);
}
)GLSL";

// kLitFS with the albedo from the mesh's materials (u_baseTex: sRGB texture, read linear); with
// SCALP_HAIR (kScalpHairDefine) also the head's hair region, with HAIR_ONLY only that.
const char* const kMeshMatFS = PONYHOP_EMIT R"GLSL(
in vec3 v_pos;
in vec3 v_normal;
in vec4 v_color;
in vec2 v_uv;
flat in vec4 v_colorSpec;
flat in vec2 v_shinRim;
uniform sampler2D u_baseTex;
uniform int u_hasTex;
#ifdef SCALP_HAIR
uniform vec3 u_hairColor;    // linear
uniform vec2 u_hairShading;  // highlight strength, shift
uniform vec3 u_hairAxis;     // world, unit: from the head's centre towards the ponytail's anchor
#endif
void main() {
  vec3 N = normalize(v_normal);
  if (!gl_FrontFacing) N = -N;
  vec3 key, rest;
#ifndef HAIR_ONLY
  vec3 albedo = v_colorSpec.rgb * v_color.rgb;
  if (u_hasTex != 0) albedo *= texture(u_baseTex, v_uv).rgb;
  shadeTerms(v_pos, N, albedo, v_colorSpec.a, v_shinRim.x, v_shinRim.y, key, rest);
#endif
#ifdef SCALP_HAIR
  // A head's hair region (MeshData::hair, in the colour's alpha: 0 skin .. 1 hair) shaded as the
  // strands are, combed up into the ponytail the way the grooves run: along the meridians about
  // the axis from the head's centre to the anchor, i.e. that axis projected onto the surface's
  // plane (on a sphere, exactly the direction towards the pole). The hair's own shadowing between
  // strands darkens it as the strands' occlusion does the inside of the tail. HAIR_ONLY: triangles
  // all hair, without the skin's terms (llvmpipe would run them, and the branch, for nothing).
  vec3 T = u_hairAxis - dot(u_hairAxis, N) * N;
  T = dot(T, T) > 1e-12 ? normalize(T) : normalize(cross(N, abs(N.z) < 0.9 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0)));
  vec3 hairKey, hairRest;
  strandTerms(v_pos, T, N, u_hairColor, 0.6, u_hairShading, hairKey, hairRest);
#ifdef HAIR_ONLY
  key = hairKey;
  rest = hairRest;
#else
  key = mix(key, hairKey, v_color.a);
  rest = mix(rest, hairRest, v_color.a);
#endif
#endif
  emit(v_pos, N, key, rest);
}
)GLSL";

// ---------------------------------------------------------------------------------------------
// [SECTION] Hair
// Hair (engine/hair.h): strand vertices sit on the strand's centre line and are pushed sideways by
// their signed half width, across the strand and the view (a ribbon that always faces the camera,
// or the light in the shadow pass); tube vertices (half width 0) stay where they are.
const char* const kHairVS = R"GLSL(
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_tangent;
layout(location = 2) in vec3 a_normal;
layout(location = 3) in vec3 a_color;
layout(location = 4) in vec2 a_widthOcclusion;  // signed half width (m), occlusion
uniform mat4 u_viewProj;
uniform vec3 u_eye;
uniform int u_faceLight;      // 1: shadow pass, face along u_faceDir
uniform vec3 u_faceDir;
uniform vec2 u_minHalfWidth;  // m, + m per metre of distance to the eye
uniform vec4 u_clipPlane;
out vec3 v_pos;
out vec3 v_tangent;
out vec3 v_normal;
out vec3 v_color;
out float v_occlusion;
void main() {
  vec3 P = a_pos;
  vec3 T = normalize(a_tangent);
  float w = a_widthOcclusion.x;
  if (w != 0.0) {
    vec3 V = u_faceLight == 1 ? -u_faceDir : u_eye - P;
    float dist = u_faceLight == 1 ? 0.0 : length(V);
    vec3 S = cross(T, V);
    S = length(S) > 1e-9 ? normalize(S) : normalize(cross(T, a_normal));
    float hw = max(abs(w), u_minHalfWidth.x + u_minHalfWidth.y * dist);
    P += S * sign(w) * hw;
  }
  v_pos = P;
  v_tangent = T;
  v_normal = a_normal;
  v_color = a_color;
  v_occlusion = a_widthOcclusion.y;
  gl_ClipDistance[0] = dot(u_clipPlane, vec4(P, 1.0));
  gl_Position = u_viewProj * vec4(P, 1.0);
}
)GLSL";

// Hair strands, shaded by strandTerms().
const char* const kHairFS = PONYHOP_EMIT R"GLSL(
in vec3 v_pos;
in vec3 v_tangent;
in vec3 v_normal;
in vec3 v_color;
in float v_occlusion;
uniform vec2 u_hairShading;  // highlight strength, shift
void main() {
  vec3 N = normalize(v_normal);
  vec3 key, rest;
  strandTerms(v_pos, normalize(v_tangent), N, v_color, v_occlusion, u_hairShading, key, rest);
  emit(v_pos, N, key, rest);  // the clump normal as it is, whichever side is seen
}
)GLSL";

// ---------------------------------------------------------------------------------------------
// [SECTION] The ground, the deferred shading, the upsampled ground, the background, the ground's shadow
// The ground: a square on the plane z = u_groundZ around the point looked at, as wide as the fade,
// drawn after the objects. Its depth comes from rasterization, so the early depth test skips every
// pixel an object covers (no shading wasted), and it still hides whatever is below the ground (its
// fragments are nearer there). The background gradient fills what is left (kBackgroundFS at the
// far plane), after it. Single-sample frames shade it at half resolution, alone, before the
// objects (kGroundUpFS, render_passes.cpp).
const char* const kGroundVS = R"GLSL(
uniform mat4 u_viewProj;
uniform mat4 u_lightViewProj;
uniform vec3 u_quadCenter;  // on the ground plane
uniform float u_quadHalf;   // m
uniform float u_quadInner;  // m; > 0: the ring between this square and the u_quadHalf one
out vec3 v_world;
out vec2 v_shadowUv;  // light-space xy: affine in the point for the orthographic light, so exact per vertex
void main() {
  vec2 c = vec2(float(gl_VertexID & 1), float((gl_VertexID >> 1) & 1)) * 2.0 - 1.0;  // a strip of 4
  float h = u_quadHalf;
  if (u_quadInner > 0.0) {  // a strip of 10: outer and inner corner in turn, around and back to the first
    int k = (gl_VertexID >> 1) & 3;
    c = vec2(k == 1 || k == 2 ? 1.0 : -1.0, k >= 2 ? 1.0 : -1.0);
    h = (gl_VertexID & 1) == 1 ? u_quadInner : u_quadHalf;
  }
  v_world = vec3(u_quadCenter.xy + c * h, u_quadCenter.z);
  vec4 s = u_lightViewProj * vec4(v_world, 1.0);
  v_shadowUv = s.xy / s.w * 0.5 + 0.5;
  gl_Position = u_viewProj * vec4(v_world, 1.0);
}
)GLSL";

const char* const kGroundFS = R"GLSL(
in vec3 v_world;
in vec2 v_shadowUv;
out vec4 o_color;
uniform int u_transparent;     // 1: no background (alpha 0 where the ground has faded out)
uniform vec3 u_groundAlbedo;   // linear
uniform float u_gridSpacing;   // m (0: plain)
uniform vec3 u_fadeCenter;     // point the fade distance is measured from
uniform vec2 u_fade;           // start, end of the fade into the background (m)
uniform sampler2D u_groundShadow;  // shadowFactor() on the ground, in light-space xy

// Every ground pixel runs this shader, and llvmpipe runs both sides of every branch: it is written
// without branches and without pow() (each pow is a log and an exp per channel on the CPU).

// Box-filtered checker (integral of the square wave over the pixel footprint): no moire and no
// shimmering towards the horizon, without a texture.
float filteredChecker(vec2 p) {
  vec2 w = max(fwidth(p), vec2(1e-5));
  vec2 i = 2.0 * (abs(fract((p - 0.5 * w) * 0.5) - 0.5) - abs(fract((p + 0.5 * w) * 0.5) - 0.5)) / w;
  return 0.5 - 0.5 * i.x * i.y;  // 0 or 1 per square, blended at edges
}


// Compiled with GROUND_NEAR: for the part of the ground nearer the fade's centre than its start
// (f = 0: no fade, no background); with GROUND_LIT as well: where the shadow texture is 1 (sh = 1).
// The same colours, for less work per pixel (drawGroundParts in render_passes.cpp draws each part with its program).
void main() {
  vec3 P = v_world;
#ifdef GROUND_NEAR
  const float f = 0.0;
#else
  vec3 bg = background(gl_FragCoord.y / u_viewport.y);
  float f = smoothstep(u_fade.x, u_fade.y, length(P.xy - u_fadeCenter.xy));
#endif
  float grid = step(1e-9, u_gridSpacing);
  float k = filteredChecker(P.xy / max(u_gridSpacing, 1e-9));
  vec3 albedo = u_groundAlbedo * mix(1.0, mix(0.93, 1.05, k), grid);  // checker: subtle, about +-6 %
  // shadeTerms() of kCommonFS for the plane (N = +z, specular 0.04, shininess 16, no rim), with the
  // shadow read from the per-frame ground shadow texture instead of a search per pixel.
  vec3 V = normalize(u_eye - P);
  vec3 L = -u_lightDir;
  float ndl = max(L.z, 0.0);
#ifdef GROUND_LIT
  float sh = step(1e-30, ndl);
#else
  vec2 c = v_shadowUv;
  float inside = step(0.0, c.x) * step(c.x, 1.0) * step(0.0, c.y) * step(c.y, 1.0) * float(u_shadowsOn != 0);
  float sh = mix(1.0, texture(u_groundShadow, c).r, inside) * step(1e-30, ndl);
#endif
  vec3 H = normalize(L + V);
  float h2 = max(H.z, 0.0);
  h2 *= h2;
  h2 *= h2;
  h2 *= h2;  // H.z^8
  float spec = 0.04 * 3.0 * (h2 * h2) * ndl;  // (16 + 8) / 8 * H.z^16
  vec3 key = u_lightColor * sh * (albedo * ndl + vec3(spec));
  vec3 fill = u_fillColor * albedo * max(-u_fillDir.z, 0.0);
  vec3 col = linearToSrgbFast(toneMap(key + fill + albedo * u_skyAmbient));
#ifdef GROUND_NEAR
  o_color = vec4(col, 1.0);
#else
  // Faded into the background: its colour exactly, so the square's edge is unseen.
  vec4 gone = u_transparent != 0 ? vec4(0.0) : vec4(bg, 1.0);
  o_color = f >= 1.0 ? gone : vec4(mix(col, bg, f), 1.0);
#endif
}
)GLSL";

// The ground at full resolution without a pass of its own (gridGroundPass): a grid of screen
// cells (u_gridCell pixels a side) over the rows below u_gridTop, each corner the ground point
// seen through it, lit there for both squares of the checker (kGroundFS's lighting, tone curve,
// fade and background); each pixel mixes its cell's two interpolated colours by the checker
// (kGridFS). Everything but the checker varies over metres of ground, so a cell's corners carry
// it; the ground point is perspective-interpolated exactly (every corner is on the plane). With
// GRID_SHADOWED (where the ground's shadow may fall): the two parts of the radiance instead, and
// the pixel looks the shadow up and finishes the colour.
const char* const kGridVS = R"GLSL(
uniform mat4 u_viewProj;
uniform mat4 u_invViewProj;
uniform mat4 u_lightViewProj;
uniform vec2 u_viewport;
uniform float u_gridCell;   // pixels
uniform float u_gridTop;    // the first pixel row (from the bottom) above the grid
uniform int u_gridCols;
uniform float u_groundZ;
uniform vec3 u_eye;
uniform vec3 u_lightDir;
uniform vec3 u_lightColor;
uniform vec3 u_fillDir;
uniform vec3 u_fillColor;
uniform vec3 u_skyAmbient;
uniform float u_exposure;
uniform vec3 u_bgTop;
uniform vec3 u_bgBottom;
uniform vec3 u_groundAlbedo;
uniform float u_gridSpacing;
uniform vec3 u_fadeCenter;
uniform vec2 u_fade;
out vec2 v_cell;    // the checker's coordinate (kGridFS)
out vec4 v_filter;  // 1 / the ramp's width in v_cell's units, and the contrast, per axis
#ifdef GRID_SHADOWED
out vec2 v_shadowUv;
out vec3 v_keyA, v_keyB;    // the key light's part before the shadow, checker value 0 and 1
out vec3 v_restA, v_restB;  // the rest
out vec4 v_bgFade;          // the background and the fade into it
#else
out vec3 v_colA;  // the colour of a square with checker value 0
out vec3 v_colB;  // ... and 1
#endif
// kCommonFS's toneMap() and background(), and its linearToSrgbFast(), for the corners.
vec3 toneMap(vec3 x) {
  x *= u_exposure;
  return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}
vec3 background(float y) {
  float t = smoothstep(0.0, 1.0, clamp(y, 0.0, 1.0));
  return mix(u_bgBottom, u_bgTop, t);
}
vec3 linearToSrgbFast(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  vec3 s1 = sqrt(c), s2 = sqrt(s1), s3 = sqrt(s2);
  vec3 g = -0.01756295 * c + 0.64236556 * s1 + 0.71211042 * s2 - 0.3368699 * s3;
  return mix(c * 12.92, g, step(0.0031308, c));
}
// kGroundFS's two parts of the radiance at P for checker value k, lit.
void groundTerms(vec3 P, float k, out vec3 key, out vec3 rest) {
  float grid = step(1e-9, u_gridSpacing);
  vec3 albedo = u_groundAlbedo * mix(1.0, mix(0.93, 1.05, k), grid);
  vec3 V = normalize(u_eye - P);
  vec3 L = -u_lightDir;
  float ndl = max(L.z, 0.0);
  vec3 H = normalize(L + V);
  float h2 = max(H.z, 0.0);
  h2 *= h2;
  h2 *= h2;
  h2 *= h2;
  float spec = 0.04 * 3.0 * (h2 * h2) * ndl;
  key = u_lightColor * step(1e-30, ndl) * (albedo * ndl + vec3(spec));
  rest = u_fillColor * albedo * max(-u_fillDir.z, 0.0) + albedo * u_skyAmbient;
}
// The ground point seen through pixel position px (from the bottom left).
vec3 groundAt(vec2 px) {
  vec2 ndc = px / u_viewport * 2.0 - 1.0;
  vec4 a = u_invViewProj * vec4(ndc, -1.0, 1.0), b = u_invViewProj * vec4(ndc, 1.0, 1.0);
  a.xyz /= a.w;
  b.xyz /= b.w;
  vec3 d = b.xyz - a.xyz;
  return vec3(a.xy + d.xy * ((u_groundZ - a.z) / d.z), u_groundZ);
}
void main() {
  // The corner's number (the index drawn): u_gridCols + 1 corners a row, from the bottom left.
  int cx = gl_VertexID - (u_gridCols + 1) * (gl_VertexID / (u_gridCols + 1)), cy = gl_VertexID / (u_gridCols + 1);
  // The last column and row end at the viewport's edge and half a pixel over the grid's top
  // (the scissor cuts what is over).
  vec2 px = min(vec2(float(cx), float(cy)) * u_gridCell, vec2(u_viewport.x, u_gridTop + 0.5));
  vec3 P = groundAt(px);
  // The checker's footprint: fwidth() of its coordinate, from the ground points a pixel to the
  // right and a pixel up.
  float inv = 1.0 / max(u_gridSpacing, 1e-9);
  vec2 c = P.xy * inv;
  vec2 fw = (abs(groundAt(px + vec2(1.0, 0.0)).xy * inv - c) + abs(groundAt(px + vec2(0.0, 1.0)).xy * inv - c));
  vec2 w = max(fw * 3.5, vec2(1e-5));  // the ramp: 3.5 pixels' footprint (about the half-resolution ground's box and bilinear tap)
  v_cell = c * 0.5 + 0.25;
  // In v_cell's units (half a checker's coordinate) the ramp is (1 - 4 q) / w (kGridFS); its
  // contrast goes to 0 as it nears two squares (the box filter's value at a square's centre).
  v_filter = vec4(1.0 / w, clamp(2.0 - w, 0.0, 1.0));
  vec3 bg = background(px.y / u_viewport.y);
  float f = smoothstep(u_fade.x, u_fade.y, length(P.xy - u_fadeCenter.xy));
  vec3 keyA, restA, keyB, restB;
  groundTerms(P, 0.0, keyA, restA);
  groundTerms(P, 1.0, keyB, restB);
#ifdef GRID_SHADOWED
  vec4 s = u_lightViewProj * vec4(P, 1.0);
  v_shadowUv = s.xy / s.w * 0.5 + 0.5;
  v_keyA = keyA;
  v_keyB = keyB;
  v_restA = restA;
  v_restB = restB;
  v_bgFade = vec4(bg, f);
#else
  v_colA = f >= 1.0 ? bg : mix(linearToSrgbFast(toneMap(keyA + restA)), bg, f);
  v_colB = f >= 1.0 ? bg : mix(linearToSrgbFast(toneMap(keyB + restB)), bg, f);
#endif
  gl_Position = u_viewProj * vec4(P, 1.0);
}
)GLSL";
const char* const kGridFS = R"GLSL(
in vec2 v_cell;
in vec4 v_filter;
#ifdef GRID_SHADOWED
in vec2 v_shadowUv;
in vec3 v_keyA, v_keyB, v_restA, v_restB;
in vec4 v_bgFade;
uniform sampler2D u_groundShadow;
#else
in vec3 v_colA;
in vec3 v_colB;
#endif
out vec4 o_color;
void main() {
  // The checker, 0 or 1 a square: q is 0 at a square's centre, 0.25 at its edges, 0.5 at the next
  // centre; each edge a linear ramp (the box filter of a step).
  vec2 q = abs(fract(v_cell) - 0.5);
  vec2 i = clamp((1.0 - 4.0 * q) * v_filter.xy, -1.0, 1.0) * v_filter.zw;
  float k = 0.5 - 0.5 * i.x * i.y;
#ifdef GRID_SHADOWED
  vec2 c = v_shadowUv;
  float inside = step(0.0, c.x) * step(c.x, 1.0) * step(0.0, c.y) * step(c.y, 1.0) * float(u_shadowsOn != 0);
  float sh = mix(1.0, texture(u_groundShadow, c).r, inside);
  vec3 col = linearToSrgbFast(toneMap(mix(v_restA, v_restB, k) + mix(v_keyA, v_keyB, k) * sh));
  o_color = vec4(v_bgFade.w >= 1.0 ? v_bgFade.rgb : mix(col, v_bgFade.rgb, v_bgFade.w), 1.0);
#else
  o_color = vec4(mix(v_colA, v_colB, k), 1.0);
#endif
}
)GLSL";

// The deferred shading pass (single-sample frames with shadows): once per pixel where an object
// is (the depth test passes only there), the shadow of the visible surface and the finished
// colour, from what the lit shaders wrote with SPLIT_LIGHT (PONYHOP_EMIT).
const char* const kDeferredFS = R"GLSL(
uniform sampler2D u_surface;
uniform sampler2D u_key;
uniform sampler2D u_rest;
out vec4 o_color;
vec3 unpackNormal(float v) {
  float b = floor(v / 4096.0);
  vec2 p = vec2(v - b * 4096.0, b) / 4095.0 * 2.0 - 1.0;
  vec3 n = vec3(p, 1.0 - abs(p.x) - abs(p.y));
  float t = max(-n.z, 0.0);
  n.xy += vec2(n.x >= 0.0 ? -t : t, n.y >= 0.0 ? -t : t);
  return normalize(n);
}
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 s = texelFetch(u_surface, p, 0);
  vec3 key = texelFetch(u_key, p, 0).rgb, rest = texelFetch(u_rest, p, 0).rgb;
#ifdef SHADOW_CLASSIFY
  // The first of two passes: finish the pixels whose shadow is known without the filter (no key
  // light at all; nothing above the surface: fully lit; the umbra: shadowFactor() 0, the colour
  // `rest` as the second pass computes it) and leave the others, by discarding them, to the
  // second pass, the whole shadowFactor() (deferredLightPass).
  float known = max(key.r, max(key.g, key.b)) > 0.0 ? shadowKnown(s.xyz, unpackNormal(s.w)) : 1.0;
  if (known == 0.5) discard;
  o_color = vec4(linearToSrgbFast(toneMap(known == 0.0 ? rest : key + rest)), 1.0);
#else
  o_color = vec4(linearToSrgbFast(toneMap(key * shadowFactor(s.xyz, unpackNormal(s.w)) + rest)), 1.0);
#endif
}
)GLSL";

// The ground shaded at half resolution (over the background), brought to full resolution
// (upsampleGroundPass): before the objects, over the whole frame, a bilinear tap of it per pixel at the
// same place in the frame. The texture coordinate is a plain input, nothing computed from it.
const char* const kGroundUpVS = R"GLSL(
out vec2 v_uv;
void main() {
  vec2 c = vec2(float(gl_VertexID & 1), float((gl_VertexID >> 1) & 1));  // a strip of 4
  v_uv = c;
  gl_Position = vec4(c * 2.0 - 1.0, 0.0, 1.0);
}
)GLSL";
const char* const kGroundUpFS = R"GLSL(
uniform sampler2D u_groundLo;
in vec2 v_uv;
out vec4 o_color;
void main() { o_color = texture(u_groundLo, v_uv); }
)GLSL";

// The background gradient, at the far plane after everything else: where nothing was drawn.
const char* const kBackgroundFS = R"GLSL(
out vec4 o_color;
void main() {
  o_color = vec4(background(gl_FragCoord.y / u_viewport.y), 1.0);
}
)GLSL";

// The ground's shadow, once per frame, into a small texture laid over the shadow map's square:
// the texel at light-space (x, y) holds shadowFactor() of the ground point on that light ray.
// With SHADOW_CLASSIFY: the first of two passes, shadowClass() only; it writes the fully lit and
// umbra texels and marks the others (depth 0) for the second, the whole shadowFactor(), which the
// depth test lets through only there.
const char* const kGroundShadowFS = R"GLSL(
out vec4 o_color;
uniform mat4 u_invLightViewProj;
uniform float u_groundZ;
uniform vec2 u_groundShadowSize;
void main() {
  vec2 ndc = gl_FragCoord.xy / u_groundShadowSize * 2.0 - 1.0;
  vec4 a = u_invLightViewProj * vec4(ndc, -1.0, 1.0), b = u_invLightViewProj * vec4(ndc, 1.0, 1.0);
  a.xyz /= a.w;
  b.xyz /= b.w;
  float t = abs(b.z - a.z) > 1e-12 ? (u_groundZ - a.z) / (b.z - a.z) : 0.0;
  vec3 P = mix(a.xyz, b.xyz, t);
#ifdef SHADOW_CLASSIFY
  float v = shadowClass(P, vec3(0.0, 0.0, 1.0));
  o_color = vec4(v, 0.0, 0.0, 1.0);
  gl_FragDepth = v == 0.5 ? 0.0 : 1.0;
#else
  o_color = vec4(shadowFactor(P, vec3(0.0, 0.0, 1.0)), 0.0, 0.0, 1.0);
#endif
}
)GLSL";

// ---------------------------------------------------------------------------------------------
// [SECTION] Post-process anti-aliasing
// Post-process anti-aliasing of the finished (display-encoded) frame, after the idea of Lottes'
// FXAA: where the local luma contrast is high, the edge's direction is estimated from the 2x2
// corner lumas and the pixel is replaced by bilinear taps along that edge; a 4-tap average is
// kept when it stays inside the local luma range, a 2-tap one otherwise (so thin features are
// not washed out). Flat pixels pass through unchanged. With POST_EDGES: the first of two passes,
// which discards the flat pixels, so that only the others get the region's depth (a mark for the
// second, the filter, under depth test EQUAL). Both read a copy of the frame and write it in place.
const char* const kPostAaFS = R"GLSL(
out vec4 o_color;
uniform sampler2D u_frame;
uniform vec2 u_texel;  // 1 / size
float luma(vec3 c) { return dot(c, vec3(0.299, 0.587, 0.114)); }
void main() {
  // Unfiltered fetches for the 2x2 corners and the centre (a software rasterizer pays for every
  // bilinear tap); the corners are clamped to the frame.
  vec2 uv = gl_FragCoord.xy * u_texel;
  ivec2 p = ivec2(gl_FragCoord.xy), hi = textureSize(u_frame, 0) - 1;
  vec4 cM = texelFetch(u_frame, p, 0);  // alpha < 1 only in transparent frames (premultiplied)
  float lM = luma(cM.rgb);
  float lNW = luma(texelFetch(u_frame, clamp(p + ivec2(-1, 1), ivec2(0), hi), 0).rgb);
  float lNE = luma(texelFetch(u_frame, clamp(p + ivec2(1, 1), ivec2(0), hi), 0).rgb);
  float lSW = luma(texelFetch(u_frame, clamp(p + ivec2(-1, -1), ivec2(0), hi), 0).rgb);
  float lSE = luma(texelFetch(u_frame, clamp(p + ivec2(1, -1), ivec2(0), hi), 0).rgb);
  float lMin = min(lM, min(min(lNW, lNE), min(lSW, lSE)));
  float lMax = max(lM, max(max(lNW, lNE), max(lSW, lSE)));
#ifdef POST_EDGES
  // First pass: the pixels without an edge are final (the same test as below); the others keep
  // this fragment's depth, the mark.
  if (lMax - lMin < max(1.0 / 24.0, lMax * 0.125)) discard;
  o_color = cM;
  return;
#endif
  if (lMax - lMin < max(1.0 / 24.0, lMax * 0.125)) {  // no edge here
    o_color = cM;
    return;
  }
  vec2 dir = vec2(-((lNW + lNE) - (lSW + lSE)), (lNW + lSW) - (lNE + lSE));
  float reduce = max((lNW + lNE + lSW + lSE) * 0.25 * 0.125, 1.0 / 128.0);
  float scale = 1.0 / (min(abs(dir.x), abs(dir.y)) + reduce);
  dir = clamp(dir * scale, vec2(-8.0), vec2(8.0)) * u_texel;
  vec4 a = 0.5 * (texture(u_frame, uv + dir * (1.0 / 3.0 - 0.5)) + texture(u_frame, uv + dir * (2.0 / 3.0 - 0.5)));
  vec4 b = 0.5 * a + 0.25 * (texture(u_frame, uv - dir * 0.5) + texture(u_frame, uv + dir * 0.5));
  float lB = luma(b.rgb);
  o_color = (lB < lMin || lB > lMax) ? a : b;
}
)GLSL";

// ---------------------------------------------------------------------------------------------
// [SECTION] The full-screen triangle
const char* const kFullscreenVS = R"GLSL(
void main() {
  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
  gl_Position = vec4(p, 1.0, 1.0);
}
)GLSL";

// The post filter's regions (Renderer::Impl::postFilterRegions): triangles already in normalized
// device coordinates, at the far plane (glDepthRange places them).
const char* const kPostVS = R"GLSL(
layout(location = 0) in vec3 a_pos;
void main() { gl_Position = vec4(a_pos.xy, 1.0, 1.0); }
)GLSL";

// ---------------------------------------------------------------------------------------------
// [SECTION] Debug lines, depth only
const char* const kLinesVS = R"GLSL(
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_color;
uniform mat4 u_viewProj;
out vec3 v_color;
void main() {
  v_color = a_color;
  gl_Position = u_viewProj * vec4(a_pos, 1.0);
}
)GLSL";

const char* const kLinesFS = R"GLSL(
in vec3 v_color;
out vec4 o_color;
void main() { o_color = vec4(v_color, 1.0); }
)GLSL";

const char* const kDepthFS = R"GLSL(
void main() {}
)GLSL";

// ---------------------------------------------------------------------------------------------
// [SECTION] Compiling and linking
static GLuint compile(GLenum stage, const char* const* parts, int count, const char* name, std::string* err) {
  GLuint s = glCreateShader(stage);
  glShaderSource(s, count, parts, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &n);
    std::vector<char> log(size_t(std::max(n, 1)));
    glGetShaderInfoLog(s, GLsizei(log.size()), nullptr, log.data());
    if (err)
      *err =
          std::string("shader ") + name + (stage == GL_VERTEX_SHADER ? " (vertex)" : " (fragment)") + ": " + log.data();
    glDeleteShader(s);
    return 0;
  }
  return s;
}

unsigned buildProgram(const char* name, const char* vs, const char* fs, std::string* err, const char* defines) {
  static const char* const kHeader = "#version 330 core\n";
  const char* vparts[] = {kHeader, defines ? defines : "", vs};
  const char* fparts[] = {kHeader, defines ? defines : "", "precision highp float;\n", kCommonFS, fs};
  GLuint v = compile(GL_VERTEX_SHADER, vparts, 3, name, err);
  if (!v) return 0;
  GLuint f = compile(GL_FRAGMENT_SHADER, fparts, 5, name, err);
  if (!f) {
    glDeleteShader(v);
    return 0;
  }
  GLuint p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &n);
    std::vector<char> log(4096);
    glGetProgramInfoLog(p, GLsizei(log.size()), nullptr, log.data());
    if (err) *err = std::string("shader ") + name + " (link): " + log.data();
    glDeleteProgram(p);
    return 0;
  }
  return p;
}

}  // namespace ponyhop::shaders
