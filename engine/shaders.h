// GLSL 3.30 core sources of the renderer (raw strings in shaders.cpp) and a program builder.
#pragma once

#include <string>

namespace ponyhop::shaders {

// Vertex shaders.
extern const char* const kMeshVS;        // meshes and boxes: per-draw model matrix (uniforms)
extern const char* const kMeshMatVS;     // meshes with their own colours/texture coordinates
extern const char* const kCapsuleVS;     // spheres / capsules / tapered capsules: one instanced draw
extern const char* const kFullscreenVS;  // full-screen triangle from gl_VertexID (ground shadow pass)
extern const char* const kPostVS;        // the post filter's regions: triangles given in NDC
extern const char* const kGroundUpVS;    // the whole viewport as a strip of 4, with its texture coordinates
extern const char* const kGridVS;        // the ground as a screen grid lit at its corners (gridGroundPass)
extern const char* const kGroundVS;      // the ground square (a strip of 4 from gl_VertexID)
extern const char* const kLinesVS;       // debug lines
extern const char* const kHairVS;        // hair strands (camera- or light-facing ribbons) and core tube
// Fragment shaders.
extern const char* const kLitFS;           // Blinn-Phong + rim, shadowed key light, fill, hemi ambient
extern const char* const kMeshMatFS;       // kLitFS with the albedo times vertex colour and base-colour texture
extern const char* const kGroundFS;        // the checker ground fading into the background
extern const char* const kGridFS;          // the grid ground: its corners' colours mixed by the checker
extern const char* const kGroundUpFS;      // the ground shaded at half resolution, upsampled
extern const char* const kBackgroundFS;    // the background gradient (where nothing was drawn)
extern const char* const kGroundShadowFS;  // the ground's soft shadow into a small texture
extern const char* const kPostAaFS;        // post-process anti-aliasing of the finished frame
extern const char* const kLinesFS;
extern const char* const kHairFS;      // Kajiya-Kay two-lobe hair, shadowed key light, fill, ambient
extern const char* const kDepthFS;     // shadow pass (depth only)
extern const char* const kDeferredFS;  // the shadow and the colour once per visible pixel (SPLIT_LIGHT targets)

// Compiled into kLitFS / kMeshMatFS / kHairFS by `defines`: they write the visible surface and the
// two parts of its radiance into three targets for kDeferredFS instead of a colour.
inline constexpr const char* kSplitLightDefine = "#define SPLIT_LIGHT 1\n";
// Compiled into kLitFS for the convex casters (hulls, convex meshes) when the deferred shading
// runs only where another caster can shadow a pixel (objectsPass): SPLIT_LIGHT, and the fragment
// also writes its finished, fully lit colour (location 3, the main colour target).
inline constexpr const char* kSplitLitDefine = "#define SPLIT_LIGHT 1\n#define LIT_COLOR 1\n";
// Compiled into kMeshMatFS: the colour's alpha is the hair weight of a head's hair region
// (MeshData::hair), drawn as hair (u_hairColor, u_hairShading, u_hairAxis); HAIR_ONLY: triangles
// whose three corners are all hair, shaded without the skin's terms.
inline constexpr const char* kScalpHairDefine = "#define SCALP_HAIR 1\n";
inline constexpr const char* kScalpHairSplitDefine = "#define SCALP_HAIR 1\n#define SPLIT_LIGHT 1\n";
inline constexpr const char* kHairOnlyDefine = "#define SCALP_HAIR 1\n#define HAIR_ONLY 1\n";
inline constexpr const char* kHairOnlySplitDefine =
    "#define SCALP_HAIR 1\n#define HAIR_ONLY 1\n#define SPLIT_LIGHT 1\n";
// Compiled into kGroundFS: the ground nearer than the fade (no fade), and also where it is lit.
inline constexpr const char* kGroundNearDefine = "#define GROUND_NEAR 1\n";
inline constexpr const char* kGroundNearLitDefine = "#define GROUND_NEAR 1\n#define GROUND_LIT 1\n";
inline constexpr const char* kGroundLitDefine = "#define GROUND_LIT 1\n";
// The grid ground where its shadow may fall (kGridVS, kGridFS).
inline constexpr const char* kGridShadowedDefine = "#define GRID_SHADOWED 1\n";
// Compiled into kGroundShadowFS: the classifying first pass (shadowClass()).
inline constexpr const char* kShadowClassifyDefine = "#define SHADOW_CLASSIFY 1\n";
// Compiled into kPostAaFS: its first pass (flat pixels discarded, edges marked by their depth).
inline constexpr const char* kPostEdgesDefine = "#define POST_EDGES 1\n";

// Compiles and links "#version 330 core" + the given sources. Returns 0 and fills `err` (with the
// driver's log and the stage's name) on failure. Needs a current context with GL loaded.
// `defines`: lines placed before the fragment shader's sources (e.g. kSplitLightDefine).
unsigned buildProgram(const char* name, const char* vs, const char* fs, std::string* err,
                      const char* defines = nullptr);

}  // namespace ponyhop::shaders
