// A scene file says what exists; the engine builds exactly that and nothing else.
// Sections that are absent from the file (head, anchor, chain, hopper) are not built, stepped or
// drawn. Every field has a default and a unit; see docs/SCENES.md for the format.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "physics/models/chain_params.h"
#include "physics/models/guide.h"
#include "physics/models/head_collisions.h"
#include "physics/models/hopper_params.h"
#include "physics/models/keyframe_params.h"
#include "physics/models/terrain.h"
#include "physics/physics_params.h"
#include "physics/reflect.h"
#include "sim/goals.h"

namespace ponyhop {

enum class CameraMode { Fixed, Orbit, Follow };
template <>
struct EnumNames<CameraMode> {
  static constexpr std::array<std::string_view, 3> names{"fixed", "orbit", "follow"};
};

struct CameraParams {
  CameraMode mode = CameraMode::Fixed;
  Eigen::Vector3d position{0.9, -1.4, 0.55};  // m (fixed mode)
  Eigen::Vector3d target{0.0, 0.0, 0.0};      // m (fixed and orbit: the point looked at)
  double fov = 35.0;                          // deg, vertical field of view
  double orbit_distance = 1.6;                // m (orbit, follow)
  double orbit_height = 0.35;                 // m above the target (orbit, follow)
  double orbit_speed = 10.0;                  // deg/s around the target (orbit)
  double orbit_angle = -60.0;                 // deg, azimuth at t = 0 (orbit, follow), from +x toward +y
  std::string follow = "";                    // follow mode: "head", "hopper" or "chain" (its first link)

  template <class V>
  void reflect(V& v) {
    v("mode", mode, {.help = "fixed position, orbit around the target, or follow a body"});
    v("position", position, {.unit = "m", .min = -1e4, .max = 1e4, .help = "Camera position (fixed)"});
    v("target", target, {.unit = "m", .min = -1e4, .max = 1e4, .help = "Point looked at"});
    v("fov", fov, {.unit = "deg", .min = 5, .max = 120, .help = "Vertical field of view"});
    v("orbit_distance", orbit_distance,
      {.unit = "m", .min = 0.05, .max = 1e3, .help = "Distance to the target (orbit, follow)", .log = true});
    v("orbit_height", orbit_height,
      {.unit = "m", .min = -1e3, .max = 1e3, .help = "Height above the target (orbit, follow)"});
    v("orbit_speed", orbit_speed, {.unit = "deg/s", .min = -360, .max = 360, .help = "Orbit rate"});
    v("orbit_angle", orbit_angle, {.unit = "deg", .min = -360, .max = 360, .help = "Azimuth at t = 0"});
    v("follow", follow, {.help = "Body followed in follow mode: head, hopper or chain"});
  }
};

struct LightParams {
  Eigen::Vector3d direction{-0.5, 0.6, -1.0};  // toward which the key light shines (world)
  Eigen::Vector3d color{1.0, 0.96, 0.9};       // rgb 0..1
  double intensity = 2.6;                      // key light multiplier
  double ambient = 0.28;                       // hemispheric ambient / fill strength
  double fill = 0.35;                          // second, shadowless fill light from the camera side
  int shadow_size = 1024;                      // px, shadow map resolution (the most; see shadow_match)
  double shadow_softness = 1.5;                // texels, PCF filter radius
  bool shadow_match = true;                    // fewer texels when the frame cannot show them (docs/RENDERING.md)

  template <class V>
  void reflect(V& v) {
    v("direction", direction, {.min = -1, .max = 1, .help = "Direction the key light shines"});
    v("color", color, {.unit = "rgb", .min = 0, .max = 1, .help = "Key light colour"});
    v("intensity", intensity, {.min = 0, .max = 20, .help = "Key light strength"});
    v("ambient", ambient, {.min = 0, .max = 5, .help = "Sky/ground ambient strength"});
    v("fill", fill, {.min = 0, .max = 5, .help = "Fill light strength"});
    v("shadow_size", shadow_size, {.unit = "px", .min = 256, .max = 8192, .help = "Shadow map size", .log = true});
    v("shadow_softness", shadow_softness, {.unit = "texel", .min = 0, .max = 8, .help = "Shadow blur radius"});
    v("shadow_match", shadow_match,
      {.help = "No more shadow texels than the frame has pixels over the casters (at least 512, at most "
               "shadow_size; draft: half; frames with hair keep shadow_size); off: always shadow_size"});
  }
};

// How much work a frame gets (docs/RENDERING.md, "Quality"). final: the picture as configured;
// draft: no anti-aliasing, a shadow map a quarter the size with a plain 5-tap filter (no contact
// hardening): a quick preview of a long video, and the window while something moves.
enum class RenderQuality { Draft, Final };
template <>
struct EnumNames<RenderQuality> {
  static constexpr std::array<std::string_view, 2> names{"draft", "final"};
};
// Anti-aliasing when samples > 1: a post-process edge filter on the finished frame (one cheap
// full-screen pass), or multisampling with `samples` samples (costly on a software rasterizer).
enum class AntiAlias { Post, Msaa };
template <>
struct EnumNames<AntiAlias> {
  static constexpr std::array<std::string_view, 2> names{"post", "msaa"};
};

struct RenderParams {
  int width = 1280;   // px
  int height = 720;   // px
  double fps = 30.0;  // frames per second of output
  int frames = 150;   // frames rendered by `ponyhop render` without --frames
  int samples = 4;    // anti-aliasing: 1 = off; > 1 = on (MSAA samples with antialias = msaa)
  AntiAlias antialias = AntiAlias::Post;
  RenderQuality quality = RenderQuality::Final;
  Eigen::Vector3d background{0.80, 0.84, 0.88};    // rgb 0..1 (top of the gradient)
  Eigen::Vector3d ground_color{0.72, 0.72, 0.70};  // rgb 0..1
  double grid_spacing = 0.25;                      // m, ground checker size (0: plain)
  bool ground = true;                              // draw the ground plane
  double ground_height = 0.0;                      // m, height of the drawn ground plane (z)
  bool transparent = false;                        // no background: PNGs with alpha (the ground is drawn when `ground`)
  bool colliders = false;                          // draw the collision shapes and the contacts over the picture
  bool active_joints = false;                      // adaptive dynamics: ring the joints that moved in the last step
  bool goals = false;                              // draw each goal as a marker over the picture (docs/GOALS.md)

  template <class V>
  void reflect(V& v) {
    v("width", width, {.unit = "px", .min = 16, .max = 8192, .help = "Image width", .soft_min = 16, .soft_max = 3840});
    v("height", height,
      {.unit = "px", .min = 16, .max = 8192, .help = "Image height", .soft_min = 16, .soft_max = 2160});
    v("fps", fps,
      {.unit = "1/s", .min = 1, .max = 1000, .help = "Frames per second of output", .soft_min = 1, .soft_max = 240});
    v("frames", frames,
      {.min = 1, .max = 1000000, .help = "Frames rendered by default", .soft_min = 1, .soft_max = 3000});
    v("samples", samples, {.min = 1, .max = 16, .help = "Anti-aliasing: 1 = off, more = on (MSAA: samples per pixel)"});
    v("antialias", antialias, {.help = "post: an edge filter on the finished frame (cheap); msaa: multisampling"});
    v("quality", quality, {.help = "final: as configured; draft: no AA, smaller plainer shadows (previews)"});
    v("background", background, {.unit = "rgb", .min = 0, .max = 1, .help = "Background colour"});
    v("ground_color", ground_color, {.unit = "rgb", .min = 0, .max = 1, .help = "Ground colour"});
    v("grid_spacing", grid_spacing, {.unit = "m", .min = 0, .max = 100, .help = "Ground checker size (0: plain)"});
    v("ground", ground, {.help = "Draw the ground plane"});
    v("ground_height", ground_height, {.unit = "m", .min = -1e3, .max = 1e3, .help = "Height of the ground plane"});
    v("transparent", transparent,
      {.help = "No background: PNG frames with alpha (set ground false for the object alone)"});
    v("colliders", colliders,
      {.help = "Draw the collision shapes (cyan wireframes) and each contact (a red normal) over the picture"});
    v("active_joints", active_joints,
      {.help = "Adaptive dynamics: ring the joints that moved in the last step (orange) over the picture"});
    v("goals", goals,
      {.help = "Draw each goal as a marker over the picture: magenta within 0.25 s of its time, faint otherwise, "
               "and at its time a yellow line from the goal's point to it"});
  }
};

enum class UpAxis { Y, Z, Auto };
template <>
struct EnumNames<UpAxis> {
  static constexpr std::array<std::string_view, 3> names{"y", "z", "auto"};
};

// Where the head body's origin (the pivot its keyframes turn about) sits in the mesh.
enum class HeadPivot { Auto, Mesh, Bounds };
template <>
struct EnumNames<HeadPivot> {
  static constexpr std::array<std::string_view, 3> names{"auto", "mesh", "bounds"};
};

// How head.anchor_in_bounds / head.anchor give the ponytail's anchor.
enum class AnchorSpace { Bounds, Mesh };
template <>
struct EnumNames<AnchorSpace> {
  static constexpr std::array<std::string_view, 2> names{"bounds", "mesh"};
};

// Colours of the head: the file's materials or head.color.
enum class HeadMaterials { Auto, Color };
template <>
struct EnumNames<HeadMaterials> {
  static constexpr std::array<std::string_view, 2> names{"auto", "color"};
};

// The head: a mesh (any format assimp reads) on a kinematic body driven by keyframes.
// Head coordinates are the mesh file's own, before scale/rotation/offset. Placement comes from the
// head itself (sim/head_fit.h): the up axis, the head's own part of a whole-body mesh, its
// bounds, the pivot and the anchor.
struct HeadParams {
  std::string mesh = "assets/head/head.gltf";  // path, relative to the repository or the scene file
  UpAxis up_axis = UpAxis::Auto;               // the mesh's up axis (auto: what the file states, else the shape)
  double height = 0.25;                     // m, rescale so the head (not a whole body) is this tall (0: use `scale`)
  double scale = 1.0;                       // mesh units to m (when height is 0)
  Eigen::Vector3d offset{0.0, 0.0, 0.0};    // m, added after scale and rotation (body frame)
  Eigen::Vector3d rotation{0.0, 0.0, 0.0};  // deg, Euler x, y, z applied after the up-axis fix
  HeadPivot pivot = HeadPivot::Auto;  // auto: the mesh origin when it lies near the head's centre, else the centre
  AnchorSpace anchor_space = AnchorSpace::Bounds;
  // Ponytail anchor, fractions of the head's bounds (x: right 0 .. left 1, y: face 0 .. back 1,
  // z: bottom 0 .. top 1); the anchor is the head's surface point nearest to it.
  Eigen::Vector3d anchor_in_bounds{0.5, 1.0, 0.6};
  // Ponytail anchor, head coordinates (mesh units), used when anchor_space is "mesh": the default
  // head's bun (assets/head/README.md).
  Eigen::Vector3d anchor{0.0, 0.0906, -0.1140};
  // The head's part of a whole-body mesh picked by hand (mesh units, the mesh's own axes): the
  // vertices inside this box. Equal corners (the default): found from the mesh (sim/head_fit.h).
  Eigen::Vector3d box_min{0.0, 0.0, 0.0};
  Eigen::Vector3d box_max{0.0, 0.0, 0.0};
  HeadMaterials materials = HeadMaterials::Auto;
  Eigen::Vector3d color{0.93, 0.78, 0.67};  // rgb 0..1, skin
  bool scalp_hair = true;                   // the hair region the mesh marks (the default head's) drawn as hair
  AnimationParams animation;

  template <class V>
  void reflect(V& v) {
    v("mesh", mesh, {.help = "Mesh file (OBJ, glTF/GLB, FBX, PLY, STL, ...)", .apply = Apply::Restart});
    v("up_axis", up_axis,
      {.help = "The mesh's up axis (auto: what the file states after import, else the axis it stands on, else the "
               "longer of y and z)",
       .apply = Apply::Restart});
    v("height", height,
      {.unit = "m",
       .min = 0,
       .max = 100,
       .help = "Rescale so the head (above the neck of a whole body) is this tall (0: use scale)",
       .apply = Apply::Restart});
    v("scale", scale, {.min = 1e-6, .max = 1e6, .help = "Mesh units to metres", .log = true, .apply = Apply::Restart});
    v("offset", offset,
      {.unit = "m", .min = -1e3, .max = 1e3, .help = "Offset in the body frame", .apply = Apply::Restart});
    v("rotation", rotation,
      {.unit = "deg", .min = -360, .max = 360, .help = "Mesh rotation, Euler x, y, z", .apply = Apply::Restart});
    v("pivot", pivot,
      {.help = "Head body origin: auto (the mesh origin if near the head's centre), mesh, bounds (centre)",
       .apply = Apply::Restart});
    v("anchor_space", anchor_space,
      {.help = "Ponytail anchor from anchor_in_bounds (bounds) or anchor (mesh)", .apply = Apply::Restart});
    v("anchor_in_bounds", anchor_in_bounds,
      {.min = 0,
       .max = 1,
       .help = "Anchor as fractions of the head's bounds: x right..left, y face..back, z bottom..top",
       .apply = Apply::Restart});
    v("anchor", anchor,
      {.min = -1e6,
       .max = 1e6,
       .help = "Ponytail anchor in the mesh's coordinates (anchor_space mesh)",
       .apply = Apply::Restart});
    v("box_min", box_min,
      {.min = -1e6,
       .max = 1e6,
       .help = "The head's part of a whole-body mesh by hand: low corner of a box in the mesh's coordinates "
               "(equal to box_max: found from the mesh)",
       .apply = Apply::Restart});
    v("box_max", box_max,
      {.min = -1e6, .max = 1e6, .help = "High corner of the head's box (mesh coordinates)", .apply = Apply::Restart});
    v("materials", materials,
      {.help = "auto: the file's textures, vertex colours, colours when it has more than one plain colour; color: "
               "head.color"});
    v("color", color, {.unit = "rgb", .min = 0, .max = 1, .help = "Skin colour"});
    v("scalp_hair", scalp_hair,
      {.help = "Draw the hair region the mesh marks (the default head's cap, parting and bun) as hair: the first "
               "chain's colour and strand shading (false: skin)",
       .apply = Apply::Restart});
    v("animation", animation, {.help = "Keyframed motion of the head", .apply = Apply::Restart});
  }
};

// How a chain is dressed as hair (engine/hair.h): a clump of thin strands around a smooth curve
// through the joints, tied at the anchor. Drawing only; the physics never reads it.
struct HairParams {
  int strands = 110;              // count, final quality
  int strands_draft = 48;         // count, draft quality (fast previews)
  double spread = 1.6;            // the clump's radius at the tip grows by 1 + spread (0: follows the links)
  double noise = 0.35;            // per-strand waviness, in units of the local clump radius
  double width = 0.0005;          // m, a strand's width at its root (at least ~1 px is drawn)
  double highlight = 0.35;        // strength of the anisotropic highlight (0: matte)
  double highlight_shift = 0.12;  // shift of the highlight along the strand (cuticle tilt)
  double color_variation = 0.18;  // 0..1, per-strand brightness and hue spread
  Eigen::Vector3d tie_color{0.55, 0.12, 0.16};  // rgb 0..1, the hair tie at the anchor

  template <class V>
  void reflect(V& v) {
    v("strands", strands, {.min = 0, .max = 2000, .help = "Number of strands drawn (final quality)"});
    v("strands_draft", strands_draft, {.min = 0, .max = 2000, .help = "Number of strands in draft quality"});
    v("spread", spread, {.min = 0, .max = 10, .help = "How much the clump widens toward the tip"});
    v("noise", noise, {.min = 0, .max = 2, .help = "Per-strand waviness (local clump radii)"});
    v("width", width, {.unit = "m", .min = 1e-5, .max = 0.01, .help = "Strand width at its root", .log = true});
    v("highlight", highlight, {.min = 0, .max = 4, .help = "Anisotropic highlight strength"});
    v("highlight_shift", highlight_shift, {.min = -1, .max = 1, .help = "Highlight shift along the strand"});
    v("color_variation", color_variation, {.min = 0, .max = 1, .help = "Colour spread between strands"});
    v("tie_color", tie_color, {.unit = "rgb", .min = 0, .max = 1, .help = "Colour of the hair tie"});
  }
};

// The scene file's chain and hopper sections: the physics parameters (physics/) plus how they
// are drawn, under the same keys (`chain.color` sits beside `chain.links`). Physics reads only
// the base; engine/scene_draw.h reads the rest.
struct ChainSection : ChainParams {
  Eigen::Vector3d color{0.36, 0.22, 0.12};  // rgb 0..1, hair brown
  HairParams hair;

  template <class V>
  void reflect(V& v) {
    ChainParams::reflect(v);
    // Drawn from the panel's applied scene (SceneDraw::draw with a look): no rebuild.
    v("color", color, {.unit = "rgb", .min = 0, .max = 1, .help = "Hair colour", .apply = Apply::Live});
    v("hair", hair, {.help = "How the chain is drawn as hair (strands, highlight, tie)", .apply = Apply::Live});
  }
};

// One of the scene's `chains`: every field of the `chain` section, plus where on its parent it
// hangs. A listed chain attached to the head hangs at its own point in the mesh's coordinates
// (`anchor`, as head.anchor with anchor_space "mesh"); one attached to a hopper names the hopper
// by its index in scene order (`hopper`, then each of `hoppers`).
struct ChainListSection : ChainSection {
  Eigen::Vector3d anchor{0.0, 0.0906, -0.1140};  // head coordinates (mesh units): the default head's bun
  int hopper = 0;                                // attach "hopper": which hopper

  template <class V>
  void reflect(V& v) {
    ChainSection::reflect(v);
    v("anchor", anchor,
      {.min = -1e6,
       .max = 1e6,
       .help = "Where the chain hangs on the head, in the mesh's coordinates (attach head)",
       .apply = Apply::Restart});
    v("hopper", hopper,
      {.min = 0,
       .max = 1000,
       .help = "The hopper it hangs from, in scene order (attach hopper)",
       .apply = Apply::Restart});
  }
};

// What one end of a scene joint (`joints`) is fixed to.
enum class JointBody { World, Head, Chain, Hopper };
template <>
struct EnumNames<JointBody> {
  static constexpr std::array<std::string_view, 4> names{"world", "head", "chain", "hopper"};
};
enum class HopperPart { Body, Upper, Foot };
template <>
struct EnumNames<HopperPart> {
  static constexpr std::array<std::string_view, 3> names{"body", "upper", "foot"};
};

// One end of a scene joint: a point on a body.
struct JointEnd {
  JointBody body = JointBody::World;
  int chain = 0;   // body "chain": which chain, in scene order (`chain`, then each of `chains`)
  int link = -1;   // body "chain": which link, 0 at the root (-1: the last); the point is its lower end
  int hopper = 0;  // body "hopper": which hopper, in scene order (`hopper`, then each of `hoppers`)
  HopperPart part = HopperPart::Body;
  Eigen::Vector3d point{0.0, 0.0, 0.0};  // world: m, world; head: mesh coordinates; hopper: m, the part's frame

  template <class V>
  void reflect(V& v) {
    v("body", body, {.help = "What this end is fixed to: the world, the head, a chain's link end, a hopper part"});
    v("chain", chain, {.min = 0, .max = 1000, .help = "Which chain, in scene order (chain, then chains)"});
    v("link", link,
      {.min = -1, .max = 4096, .help = "Which link of the chain, 0 at the root (-1: the last): its lower end"});
    v("hopper", hopper, {.min = 0, .max = 1000, .help = "Which hopper, in scene order (hopper, then hoppers)"});
    v("part", part, {.help = "Which part of the hopper"});
    v("point", point,
      {.min = -1e6,
       .max = 1e6,
       .help = "The point: world (m) on the world, mesh coordinates on the head, the part's frame (m) on a hopper"});
  }
};

// A joint's kind: a ball joint (3 rows), or a hinge about `axis` (5 rows, physics/hinge_joint.h).
enum class JointType { Spherical, Hinge };
template <>
struct EnumNames<JointType> {
  static constexpr std::array<std::string_view, 2> names{"spherical", "hinge"};
};

// A joint the scene adds between two points on any two bodies (docs/PHYSICS.md, "Closed
// loops"): a chain's tip tied back to the head closes a loop. Its two points must meet at t = 0
// (the bodies between them are moved onto it); a loop that cannot close is refused.
struct JointSection {
  std::string name;  // named in messages
  JointType type = JointType::Spherical;
  Eigen::Vector3d axis{0.0, 0.0, 0.0};  // hinge: its axis (world, at t = 0, before assembly)
  JointEnd a, b;

  template <class V>
  void reflect(V& v) {
    v("name", name, {.help = "Name of the joint (messages)"});
    v("type", type, {.help = "spherical: a ball joint; hinge: turns only about axis"});
    v("axis", axis, {.min = -1, .max = 1, .help = "Hinge axis (world, at t = 0); type hinge only"});
    v("a", a, {.help = "First end"});
    v("b", b, {.help = "Second end"});
  }
};

struct HopperSection : HopperParams {
  Eigen::Vector3d body_color{0.86, 0.33, 0.16};  // rgb 0..1
  Eigen::Vector3d leg_color{0.62, 0.65, 0.70};
  Eigen::Vector3d foot_color{0.12, 0.12, 0.13};

  template <class V>
  void reflect(V& v) {
    HopperParams::reflect(v);
    v("body_color", body_color, {.unit = "rgb", .min = 0, .max = 1, .help = "Body colour"});
    v("leg_color", leg_color, {.unit = "rgb", .min = 0, .max = 1, .help = "Upper leg colour"});
    v("foot_color", foot_color, {.unit = "rgb", .min = 0, .max = 1, .help = "Foot colour"});
  }
};

// Collisions the scene names (docs/PHYSICS.md, "Collisions"): the ponytail's links against the
// head's mesh (a signed distance grid built from its triangles at load) and a swing cone at the
// root. Absent from the file: no collisions are built or stepped.
struct CollisionSection : HeadCollisionParams {
  bool head = true;     // the chain's links collide with the head (a chain attached to a head)
  bool ground = false;  // the hoppers' bodies and legs collide with the ground and with each other

  template <class V>
  void reflect(V& v) {
    v("head", head, {.help = "The ponytail's links collide with the head's mesh (a chain attached to a head)"});
    v("ground", ground,
      {.help = "Every hopper's body and legs collide with the ground z = 0 and with the other hoppers (the toe has "
               "its own contact)"});
    HeadCollisionParams::reflect(v);
  }
};

// Boxes on the ground (physics/models/terrain.h): steps, and slopes as tilted boxes. The hoppers' toes
// stand on them; with collision.ground their bodies and legs meet them too. Drawn as boxes.
struct TerrainSection {
  std::vector<TerrainBox> boxes;
  Eigen::Vector3d color{0.42, 0.36, 0.3};  // linear RGB

  template <class V>
  void reflect(V& v) {
    v("boxes", boxes, {.help = "Boxes standing on or in the ground plane"});
    v("color", color, {.unit = "rgb", .min = 0, .max = 1, .help = "Colour of the boxes", .apply = Apply::Live});
  }
};

struct Scene {
  std::string path;       // the file it was read from ("" when built in code)
  std::string name;       // a short title
  double duration = 5.0;  // s, simulated by `ponyhop sim` without --duration
  RenderParams render;
  CameraParams camera;
  LightParams light;
  PhysicsParams physics;
  std::optional<HeadParams> head;
  std::optional<AnchorParams> anchor;
  std::optional<ChainSection> chain;
  std::vector<ChainListSection> chains;  // more chains in the same world (each with its own attachment)
  std::optional<HopperSection> hopper;
  std::vector<HopperSection> hoppers;  // more hoppers in the same world (each with its own position)
  std::vector<JointSection> joints;    // spherical joints and hinges between points on two bodies (closed loops)
  std::optional<CollisionSection> collision;
  std::optional<TerrainSection> terrain;
  std::vector<std::string> notes;  // what the reader chose for the user (not a field), shown on stderr

  std::vector<Goal> goals;           // where points must be at given times (sim/goals.h, docs/GOALS.md)
  std::optional<GuideParams> guide;  // the solved torques that meet them (`ponyhop solve`)

  template <class V>
  void reflect(V& v) {
    v("name", name, {.help = "Title of the scene", .apply = Apply::Live});
    v("duration", duration,
      {.unit = "s",
       .min = 0,
       .max = 1e6,
       .help = "Simulated time for `ponyhop sim`",
       .apply = Apply::Live,
       .soft_min = 0,
       .soft_max = 120});
    v("render", render, {.help = "Output image settings", .apply = Apply::Live});
    v("camera", camera, {.help = "Camera", .apply = Apply::Live});
    v("light", light, {.help = "Lighting", .apply = Apply::Live});
    v("physics", physics, {.help = "Simulation settings"});
    v("goals", goals,
      {.help = "Where a point must be at a time (ponyhop solve meets them; docs/GOALS.md)", .apply = Apply::Live});
    v("head", head, {.help = "Keyframed kinematic head"});
    v("anchor", anchor, {.help = "Prescribed anchor point of a chain scene", .apply = Apply::Restart});
    v("chain", chain, {.help = "Chain of links (the ponytail)"});
    v("chains", chains,
      {.help = "More chains in the same world, each a chain section with its own anchor on the head or hopper index",
       .apply = Apply::Restart});
    v("hopper", hopper, {.help = "Raibert hopper (body, leg, ground contact, controller)"});
    v("hoppers", hoppers, {.help = "More hoppers in the same world, each a hopper section", .apply = Apply::Restart});
    v("joints", joints,
      {.help = "Spherical joints and hinges between points on two bodies (a chain's link end, the head, a hopper "
               "part, the world): closed loops",
       .apply = Apply::Restart});
    v("collision", collision, {.help = "Collisions: the ponytail against the head"});
    v("terrain", terrain,
      {.help = "Boxes on the ground (steps, slopes) for the hoppers' toes and, with collision.ground, their bodies",
       .apply = Apply::Restart});
    v("guide", guide,
      {.help = "Solved control (written by ponyhop solve): joint torques of the chain, commands of the hopper",
       .apply = Apply::Restart});
  }
};

// The section of the scene's i-th hopper, in the order Sim builds them: `hopper`, then `hoppers`.
inline const HopperSection& hopperSection(const Scene& scene, size_t i) {
  if (scene.hopper) return i == 0 ? *scene.hopper : scene.hoppers[i - 1];
  return scene.hoppers[i];
}

// The scene's chains in the order Sim builds them (`chain`, then each of `chains`): how many, the
// i-th one's section, and its entry in `chains` (null for `chain`).
inline size_t chainCount(const Scene& scene) { return (scene.chain ? 1 : 0) + scene.chains.size(); }
inline const ChainListSection* listedChain(const Scene& scene, size_t i) {
  return scene.chain ? (i == 0 ? nullptr : &scene.chains[i - 1]) : &scene.chains[i];
}
inline const ChainSection& chainSection(const Scene& scene, size_t i) {
  if (const ChainListSection* c = listedChain(scene, i)) return *c;
  return *scene.chain;
}
// "chain" or "chains.N": the key of the i-th chain's section, for messages.
inline std::string chainKey(const Scene& scene, size_t i) {
  return listedChain(scene, i) ? "chains." + std::to_string(i - (scene.chain ? 1 : 0)) : "chain";
}

}  // namespace ponyhop
