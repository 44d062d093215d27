// Index of this file:
// [SECTION] Helpers: field defaults, JSON, sliders, the velocity pad
// [SECTION] FieldWidgets and the section visitors: one widget per field
// [SECTION] PanelContext: the ImGui context, its font and input
// [SECTION] Panel: state, layout and build()
// [SECTION] Panel: the parts of the panel
// [SECTION] Panel: keys, mouse, the camera and the view's overlay

#include "app/panel.h"

#include <imgui.h>
#include <imgui_internal.h>  // TempInputIsActive: a slider's text shows while a value is typed

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <type_traits>

#include "app/chain_look.h"
#include "app/presets.h"
#include "engine/asset_loader.h"
#include "engine/scene_draw.h"
#include "physics/collisions.h"
#include "physics/stage_times.h"
#include "sim/data_dir.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

// ---------------------------------------------------------------------------------------------
// [SECTION] Helpers: field defaults, JSON, sliders, the velocity pad

using nlohmann::json;

// Sets every optional section, so that sceneToJson lists every field's default.
struct EmplaceAll {
  template <class T>
  void operator()(const char*, T& field, const FieldMeta&) {
    if constexpr (IsOptional<T>::value) {
      if (!field) field.emplace();
    }
  }
};

// The default of every field: the JSON of a default Scene with every section present.
const json& defaults() {
  static const json j = [] {
    Scene s;
    EmplaceAll e;
    s.reflect(e);
    return sceneToJson(s);
  }();
  return j;
}

const json* defaultOf(const std::string& key) {
  std::string ptr = "/" + key;
  std::replace(ptr.begin(), ptr.end(), '.', '/');
  const json::json_pointer p(ptr);
  return defaults().contains(p) ? &defaults().at(p) : nullptr;
}

// Field <-> JSON for the reset button (scene files hold the same representation).
template <class T>
json toJson(const T& v) {
  if constexpr (std::is_enum_v<T>) {
    return std::string(enumName(v));
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    return json::array({v.x(), v.y(), v.z()});
  } else {
    return v;
  }
}

template <class T>
bool fromJson(const json& j, T& v) {
  try {
    if constexpr (std::is_enum_v<T>) {
      return enumFromName(j.get<std::string>(), v);
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
      if (!j.is_array() || j.size() != 3) return false;
      v = Eigen::Vector3d(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
      return true;
    } else {
      v = j.get<T>();
      return true;
    }
  } catch (const json::exception&) {
    return false;
  }
}

// "orbit_distance" -> "Orbit distance".
std::string friendly(const char* name) {
  std::string s = name;
  std::replace(s.begin(), s.end(), '_', ' ');
  if (!s.empty()) s[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(s[0])));
  return s;
}

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

// ImGui formats must contain one printf conversion; a unit must not add another.
std::string withUnit(const char* fmt, const char* unit) {
  std::string u;
  for (const char* c = unit; c && *c; ++c) u += (*c == '%') ? std::string("%%") : std::string(1, *c);
  return u.empty() ? std::string(fmt) : std::string(fmt) + " " + u;
}

// The slider's range: the field's soft range when it has one (values beyond stay reachable by
// typing, Ctrl+click, up to the allowed range).
void rangeFor(const FieldMeta& meta, double& lo, double& hi) {
  lo = std::isnan(meta.soft_min) ? meta.min : std::max(meta.min, meta.soft_min);
  hi = std::isnan(meta.soft_max) ? meta.max : std::min(meta.max, meta.soft_max);
}

// A slider whose value is printed beside it, never under the knob: the slider's own text is drawn
// transparent except while a value is typed into it (Ctrl+click). `rect`: the slider's place.
struct SideSlider {
  bool changed = false;
  ImVec2 min, max;
};
SideSlider sideSlider(const char* id, ImGuiDataType type, void* v, const void* lo, const void* hi, const char* fmt,
                      ImGuiSliderFlags flags, float width, const std::string& shown) {
  const float value_w = ImGui::GetFontSize() * 7.5f;
  const float slider_w = std::max(width - value_w - ImGui::GetStyle().ItemSpacing.x, ImGui::GetFontSize() * 3.0f);
  const bool typing = ImGui::TempInputIsActive(ImGui::GetID(id));
  if (!typing) ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(0, 0, 0, 0));
  ImGui::SetNextItemWidth(slider_w);
  SideSlider r;
  r.changed = ImGui::SliderScalar(id, type, v, lo, hi, fmt, flags);
  if (!typing) ImGui::PopStyleColor();
  r.min = ImGui::GetItemRectMin();
  r.max = ImGui::GetItemRectMax();
  ImGui::SameLine();
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted(shown.c_str());
  return r;
}

void tooltip(const std::string& key, const FieldMeta& meta, const std::string& default_text) {
  if (!ImGui::IsItemHovered()) return;
  ImGui::BeginTooltip();
  ImGui::PushTextWrapPos(ImGui::GetFontSize() * 24.0f);
  if (meta.help && *meta.help) ImGui::TextUnformatted(meta.help);
  ImGui::PopTextWrapPos();
  ImGui::Separator();
  if (meta.unit && *meta.unit) ImGui::Text("Unit: %s", meta.unit);
  const bool has_min = std::isfinite(meta.min), has_max = std::isfinite(meta.max);
  if (has_min || has_max) {
    ImGui::Text("Allowed: %s .. %s", has_min ? number(meta.min).c_str() : "-inf",
                has_max ? number(meta.max).c_str() : "inf");
  }
  if (!default_text.empty()) ImGui::Text("Default: %s", default_text.c_str());
  ImGui::TextDisabled("%s  (scene file / --set)", key.c_str());
  ImGui::TextDisabled("Ctrl+click a slider to type a value");
  ImGui::EndTooltip();
}

std::vector<std::string> clipNames() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dataDir() + "/assets/animations", ec)) {
    if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// Finds double fields named vx and vy (a velocity command): they get a 2D pad.
struct FindPad {
  double* vx = nullptr;
  double* vy = nullptr;
  FieldMeta meta;
  template <class T>
  void operator()(const char* name, T& field, const FieldMeta& m) {
    if constexpr (std::is_same_v<T, double>) {
      if (std::string_view(name) == "vx") vx = &field, meta = m;
      if (std::string_view(name) == "vy") vy = &field;
    }
  }
};

// A square pad: x to the right, y up; drag to set (vx, vy), double-click for zero.
bool velocityPad(const char* id, double& vx, double& vy, double range) {
  const float size = std::min(ImGui::GetContentRegionAvail().x, 150.0f);
  const ImVec2 p0 = ImGui::GetCursorScreenPos();
  ImGui::InvisibleButton(id, ImVec2(size, size));
  const ImVec2 p1(p0.x + size, p0.y + size);
  ImDrawList* dl = ImGui::GetWindowDrawList();
  dl->AddRectFilled(p0, p1, ImGui::GetColorU32(ImGuiCol_FrameBg), 4.0f);
  const ImVec2 c(0.5f * (p0.x + p1.x), 0.5f * (p0.y + p1.y));
  dl->AddLine(ImVec2(p0.x, c.y), ImVec2(p1.x, c.y), ImGui::GetColorU32(ImGuiCol_Border));
  dl->AddLine(ImVec2(c.x, p0.y), ImVec2(c.x, p1.y), ImGui::GetColorU32(ImGuiCol_Border));
  dl->AddCircle(c, 0.25f * size, ImGui::GetColorU32(ImGuiCol_Border), 32);
  bool changed = false;
  if (ImGui::IsItemActive()) {
    const ImVec2 m = ImGui::GetIO().MousePos;
    vx = std::clamp(double((m.x - c.x) / (0.5f * size)), -1.0, 1.0) * range;
    vy = std::clamp(double((c.y - m.y) / (0.5f * size)), -1.0, 1.0) * range;
    changed = true;
  }
  if (ImGui::IsItemHovered() && ImGui::IsMouseDoubleClicked(0)) {
    vx = vy = 0.0;
    changed = true;
  }
  const ImVec2 dot(c.x + float(vx / range) * 0.5f * size, c.y - float(vy / range) * 0.5f * size);
  dl->AddLine(c, dot, ImGui::GetColorU32(ImGuiCol_PlotLines), 2.0f);
  dl->AddCircleFilled(dot, 5.0f, ImGui::GetColorU32(ImGuiCol_SliderGrabActive));
  ImGui::SameLine();
  ImGui::BeginGroup();
  ImGui::TextDisabled("Desired velocity");
  ImGui::Text("vx %+.2f m/s", vx);
  ImGui::Text("vy %+.2f m/s", vy);
  ImGui::TextDisabled("drag; double-click: 0");
  ImGui::EndGroup();
  return changed;
}

Eigen::Vector3d closestOnSegment(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                                 const Eigen::Vector3d& b, double& s_ray) {
  // Closest points of the ray o + s d (|d| = 1, s >= 0) and the segment a + u (b - a), u in [0, 1].
  const Eigen::Vector3d e = b - a, w0 = o - a;
  const double bb = d.dot(e), cc = e.dot(e), dd = d.dot(w0), ee = e.dot(w0);
  const double den = cc - bb * bb;  // |d| = 1
  double u = den > 1e-12 ? (ee - bb * dd) / den : 0.0;
  u = std::clamp(u, 0.0, 1.0);
  const Eigen::Vector3d q = a + u * e;
  s_ray = std::max(0.0, (q - o).dot(d));
  return q;
}

// A readout's time (ms), smoothed over about ten frames.
void smoothInto(double& r, double ms) { r = r <= 0.0 ? ms : 0.9 * r + 0.1 * ms; }

}  // namespace

// ---------------------------------------------------------------------------------------------
// [SECTION] FieldWidgets and the section visitors: one widget per field
// The reflect() visitor that draws one widget per field.

class FieldWidgets {
 public:
  FieldWidgets(Panel& panel, std::string prefix, std::vector<std::string> only = {}, std::vector<std::string> skip = {})
      : panel_(panel), prefix_(std::move(prefix)), only_(std::move(only)), skip_(std::move(skip)) {}

  template <class T>
  void operator()(const char* name, T& field, const FieldMeta& meta) {
    if (!only_.empty() && std::find(only_.begin(), only_.end(), name) == only_.end()) return;
    if (std::find(skip_.begin(), skip_.end(), name) != skip_.end()) return;
    const std::string key = prefix_ + name;
    ImGui::PushID(key.c_str());
    if constexpr (IsOptional<T>::value) {
      if (field) (*this)(name, *field, meta);
    } else if constexpr (IsVector<T>::value) {
      label(name, key, meta, "");
      ImGui::TextDisabled("%zu entries (edit in the scene file)", field.size());
    } else if constexpr (Reflectable<T>) {
      group(name, key, field);
    } else {
      row(name, key, field, meta);
    }
    ImGui::PopID();
  }

 private:
  template <class T>
  void group(const char* name, const std::string& key, T& field) {
    if (ImGui::TreeNodeEx(friendly(name).c_str(), ImGuiTreeNodeFlags_DefaultOpen | ImGuiTreeNodeFlags_SpanAvailWidth)) {
      FindPad pad;
      field.reflect(pad);
      if (pad.vx && pad.vy) {
        const double range = std::isfinite(pad.meta.max) ? std::min(pad.meta.max, 3.0) : 2.0;
        velocityPad("pad", *pad.vx, *pad.vy, range);
        panel_.remember(key + ".pad");
      }
      FieldWidgets inner(panel_, key + ".");
      field.reflect(inner);
      ImGui::TreePop();
    }
  }

  void label(const char* name, const std::string& key, const FieldMeta& meta, const std::string& def) {
    ImGui::AlignTextToFramePadding();
    ImGui::TextUnformatted(friendly(name).c_str());
    tooltip(key, meta, def);
    ImGui::SameLine(ImGui::GetFontSize() * 9.5f);
  }

  template <class T>
  void row(const char* name, const std::string& key, T& field, const FieldMeta& meta) {
    const json* def = defaultOf(key);
    const bool at_default = !def || toJson(field) == *def;
    const std::string def_text = def ? (def->is_string() ? def->get<std::string>() : def->dump()) : "";
    label(name, key, meta, def_text);
    const float reset_w = ImGui::GetFrameHeight();
    const float width = ImGui::GetContentRegionAvail().x - reset_w - ImGui::GetStyle().ItemSpacing.x;
    ImGui::SetNextItemWidth(width);
    if (auto slider = widget(key, field, meta, width)) {
      panel_.rects_[key] = WidgetRect{slider->min.x, slider->min.y, slider->max.x, slider->max.y};
    } else {
      panel_.remember(key);
    }
    tooltip(key, meta, def_text);
    ImGui::SameLine(ImGui::GetWindowContentRegionMax().x - reset_w);
    ImGui::SameLine();
    ImGui::BeginDisabled(at_default);
    if (ImGui::Button("R##reset", ImVec2(reset_w, reset_w)) && def) fromJson(*def, field);
    panel_.remember("reset:" + key);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Reset to the default (%s)", def_text.c_str());
    ImGui::EndDisabled();
  }

  // Sliders return their rectangle (the value is printed beside them); other widgets nothing.
  std::optional<SideSlider> widget(const std::string&, double& v, const FieldMeta& meta, float width) {
    double lo, hi;
    rangeFor(meta, lo, hi);
    if (!std::isfinite(lo) || !std::isfinite(hi)) {
      ImGui::DragScalar("##v", ImGuiDataType_Double, &v, float(std::max(std::abs(v) * 0.01, 1e-3)), nullptr, nullptr,
                        withUnit("%.4g", meta.unit).c_str());
      return std::nullopt;
    }
    const bool log = meta.log || (lo >= 0.0 && hi >= 1e3 * std::max(lo, 1e-300) && hi >= 1e3);
    ImGuiSliderFlags flags = log ? ImGuiSliderFlags_Logarithmic : 0;
    // A logarithmic slider that starts at 0 treats values below 10^-precision as 0: give it digits.
    const char* fmt = (log && lo <= 0.0) ? "%.6g" : "%.4g";
    if (log) flags |= ImGuiSliderFlags_NoRoundToFormat;
    char shown[64];
    std::snprintf(shown, sizeof shown, withUnit(fmt, meta.unit).c_str(), v);
    return sideSlider("##v", ImGuiDataType_Double, &v, &lo, &hi, fmt, flags, width, shown);
  }

  std::optional<SideSlider> widget(const std::string&, int& v, const FieldMeta& meta, float width) {
    double lo_d, hi_d;
    rangeFor(meta, lo_d, hi_d);
    const int lo = std::isfinite(lo_d) ? int(lo_d) : -1000000, hi = std::isfinite(hi_d) ? int(hi_d) : 1000000;
    char shown[64];
    std::snprintf(shown, sizeof shown, withUnit("%d", meta.unit).c_str(), v);
    return sideSlider("##v", ImGuiDataType_S32, &v, &lo, &hi, "%d", meta.log ? ImGuiSliderFlags_Logarithmic : 0, width,
                      shown);
  }

  std::optional<SideSlider> widget(const std::string&, bool& v, const FieldMeta&, float) {
    ImGui::Checkbox("##v", &v);
    return std::nullopt;
  }

  std::optional<SideSlider> widget(const std::string& key, std::string& v, const FieldMeta&, float) {
    const bool is_clip = key.size() >= 5 && key.compare(key.size() - 5, 5, ".clip") == 0;
    if (is_clip || key == "camera.follow") {
      std::vector<std::string> choices;
      if (is_clip) {
        choices = clipNames();
        choices.push_back("mesh");
        choices.push_back("");
      } else {
        choices = {"", "head", "chain", "hopper"};
      }
      const auto shown = [&](const std::string& c) {
        return c.empty() ? std::string(is_clip ? "(inline keys)" : "(auto)") : c;
      };
      if (ImGui::BeginCombo("##v", shown(v).c_str())) {
        for (const std::string& c : choices) {
          if (ImGui::Selectable(shown(c).c_str(), c == v)) v = c;
        }
        ImGui::EndCombo();
      }
      return std::nullopt;
    }
    // Text is applied when the field is left or Enter is pressed, not at every keystroke (a
    // half-typed file name would not load).
    char buf[512];
    std::snprintf(buf, sizeof buf, "%s", v.c_str());
    if (ImGui::InputText("##v", buf, sizeof buf, ImGuiInputTextFlags_EnterReturnsTrue) ||
        ImGui::IsItemDeactivatedAfterEdit()) {
      v = buf;
    }
    return std::nullopt;
  }

  std::optional<SideSlider> widget(const std::string&, Eigen::Vector3d& v, const FieldMeta& meta, float) {
    if (std::string_view(meta.unit) == "rgb") {
      float c[3] = {float(v.x()), float(v.y()), float(v.z())};
      if (ImGui::ColorEdit3("##v", c, ImGuiColorEditFlags_Float)) v = Eigen::Vector3d(c[0], c[1], c[2]);
      return std::nullopt;
    }
    const float speed = float(std::max(v.cwiseAbs().maxCoeff() * 0.005, 1e-3));
    ImGui::DragScalarN("##v", ImGuiDataType_Double, v.data(), 3, speed, &meta.min, &meta.max, "%.4g");
    return std::nullopt;
  }

  template <class E>
  requires std::is_enum_v<E> std::optional<SideSlider> widget(const std::string&, E& v, const FieldMeta&, float) {
    const auto& names = EnumNames<E>::names;
    const std::string current(enumName(v));
    if (ImGui::BeginCombo("##v", current.c_str())) {
      for (size_t i = 0; i < names.size(); ++i) {
        const std::string n(names[i]);
        if (ImGui::Selectable(n.c_str(), static_cast<size_t>(v) == i)) v = static_cast<E>(i);
      }
      ImGui::EndCombo();
    }
    return std::nullopt;
  }

  Panel& panel_;
  std::string prefix_;
  std::vector<std::string> only_, skip_;
};

// Draws one top-level section of the scene (a struct or an optional that is present).
class SectionVisitor {
 public:
  SectionVisitor(Panel& panel, const char* field, const char* title, bool open, std::vector<std::string> only = {},
                 std::vector<std::string> skip = {}, std::string prefix = "")
      : panel_(panel),
        field_(field),
        title_(title),
        open_(open),
        only_(std::move(only)),
        skip_(std::move(skip)),
        prefix_(std::move(prefix)) {}

  template <class T>
  void operator()(const char* name, T& field, const FieldMeta&) {
    if (std::string_view(name) != field_) return;
    if constexpr (IsOptional<T>::value) {
      if (field) draw(name, *field);
    } else if constexpr (Reflectable<T>) {
      draw(name, field);
    }
  }
  bool drawn = false;

 private:
  template <class T>
  void draw(const char* name, T& section) {
    drawn = true;
    if (!panel_.sectionHeader(title_, open_)) return;
    ImGui::PushID(title_);
    FindPad pad;  // a velocity command section (the hopper's) gets its 2D pad on top
    section.reflect(pad);
    if (pad.vx && pad.vy) {
      const double range = std::isfinite(pad.meta.max) ? std::min(pad.meta.max, 3.0) : 2.0;
      velocityPad("pad", *pad.vx, *pad.vy, range);
      panel_.remember(prefix_ + name + ".pad");
    }
    FieldWidgets w(panel_, prefix_ + name + ".", only_, skip_);
    section.reflect(w);
    ImGui::PopID();
    ImGui::Spacing();
  }

  Panel& panel_;
  const char* field_;
  const char* title_;
  bool open_;
  std::vector<std::string> only_, skip_;
  std::string prefix_;
};

// Opens the hopper section's command group under its own header ("Hopper commands").
class NestedSection {
 public:
  NestedSection(Panel& panel, const char* outer, const char* inner, const char* title, bool open)
      : panel_(panel), outer_(outer), inner_(inner), title_(title), open_(open) {}
  template <class T>
  void operator()(const char* name, T& field, const FieldMeta&) {
    if (std::string_view(name) != outer_) return;
    if constexpr (IsOptional<T>::value) {
      if (field) {
        SectionVisitor v(panel_, inner_, title_, open_, {}, {}, std::string(outer_) + ".");
        field->reflect(v);
      }
    }
  }

 private:
  Panel& panel_;
  const char* outer_;
  const char* inner_;
  const char* title_;
  bool open_;
};

// ---------------------------------------------------------------------------------------------
// [SECTION] PanelContext: the ImGui context, its font and input

PanelContext::PanelContext(float font_px) {
  IMGUI_CHECKVERSION();
  ctx_ = ImGui::CreateContext();
  ImGui::SetCurrentContext(ctx_);
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini in the working directory
  io.LogFilename = nullptr;
  // Key indices as GLFW numbers them (the GLFW backend sets the same), so headless input and the
  // window share one map.
  io.KeyMap[ImGuiKey_Space] = 32;
  io.KeyMap[ImGuiKey_Backspace] = 259;
  io.KeyMap[ImGuiKey_RightArrow] = 262;
  io.KeyMap[ImGuiKey_LeftArrow] = 263;
  io.KeyMap[ImGuiKey_Enter] = 257;
  io.KeyMap[ImGuiKey_Escape] = 256;
  io.KeyMap[ImGuiKey_Tab] = 258;

  ImGui::StyleColorsDark();
  ImGuiStyle& s = ImGui::GetStyle();
  s.WindowRounding = 0.0f;
  s.FrameRounding = 3.0f;
  s.GrabRounding = 3.0f;
  s.WindowBorderSize = 0.0f;
  s.FramePadding = ImVec2(6.0f, 3.0f);
  s.ItemSpacing = ImVec2(6.0f, 4.0f);
  s.IndentSpacing = 12.0f;
  s.WindowPadding = ImVec2(10.0f, 8.0f);
  s.Colors[ImGuiCol_WindowBg] = ImVec4(0.11f, 0.12f, 0.14f, 1.0f);
  s.Colors[ImGuiCol_Header] = ImVec4(0.22f, 0.30f, 0.42f, 1.0f);
  s.Colors[ImGuiCol_HeaderHovered] = ImVec4(0.28f, 0.38f, 0.52f, 1.0f);

  // DejaVu Sans (Debian's fonts-dejavu-core) reads better than ImGui's bitmap font; fall back to it.
  static const ImWchar ranges[] = {0x0020, 0x00FF, 0x2190, 0x21FF, 0x25A0, 0x25FF, 0};
  const char* font = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  std::error_code ec;
  if (std::filesystem::exists(font, ec)) {
    io.Fonts->AddFontFromFileTTF(font, font_px, nullptr, ranges);
    // The title's font: the same face, larger (Fonts[1]).
    const char* bold = "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf";
    io.Fonts->AddFontFromFileTTF(std::filesystem::exists(bold, ec) ? bold : font, font_px * 1.3f, nullptr, ranges);
  } else {
    io.Fonts->AddFontDefault();
  }
  io.Fonts->Build();  // NewFrame() needs the atlas even with no renderer (tests)
}

PanelContext::~PanelContext() { ImGui::DestroyContext(ctx_); }

void feedInput(const UiInput& in) {
  ImGuiIO& io = ImGui::GetIO();
  io.DisplaySize = ImVec2(in.width, in.height);
  io.DeltaTime = float(std::max(in.dt, 1e-4));
  io.MousePos = ImVec2(in.mouse_x, in.mouse_y);
  for (int i = 0; i < 3; ++i) io.MouseDown[i] = in.mouse_down[i];
  io.MouseWheel = in.wheel;
  io.KeyCtrl = in.ctrl;
  io.KeyShift = in.shift;
  for (bool& k : io.KeysDown) k = false;
  for (int k : in.keys_down) {
    if (k >= 0 && k < ImGuiKey_COUNT && io.KeyMap[k] >= 0) io.KeysDown[io.KeyMap[k]] = true;
  }
}

// ---------------------------------------------------------------------------------------------
// [SECTION] Panel: state, layout and build()

Panel::Panel(LiveSim& sim) : sim_(sim), preset_path_(sim.applied().path) {
  camera_ = cameraAt(sim_.applied().camera, 0.0);
}

void Panel::remember(const std::string& id) {
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  rects_[id] = WidgetRect{a.x, a.y, b.x, b.y};
}

std::optional<WidgetRect> Panel::widgetRect(const std::string& id) const {
  auto it = rects_.find(id);
  if (it == rects_.end()) return std::nullopt;
  return it->second;
}

void Panel::setSectionOpen(const std::string& title, bool open) { pending_open_[title] = open; }

void Panel::setRenderMs(double ms) { smoothInto(sim_.readouts().render_ms, ms); }

void Panel::setFrameMs(double compose_ms, double frame_ms) {
  smoothInto(sim_.readouts().compose_ms, compose_ms);
  smoothInto(sim_.readouts().frame_ms, frame_ms);
}

bool Panel::sectionHeader(const char* title, bool default_open) {
  if (auto it = pending_open_.find(title); it != pending_open_.end()) {
    ImGui::SetNextItemOpen(it->second);
    pending_open_.erase(it);
  }
  return ImGui::CollapsingHeader(title, default_open ? ImGuiTreeNodeFlags_DefaultOpen : 0);
}

void Panel::build(const PanelLayout& layout, bool advance) {
  const auto t0 = Clock::now();
  rects_.clear();
  ImGuiIO& io = ImGui::GetIO();
  const float panel_w = float(std::min(layout.panel_width, layout.width));
  shown_playback_.since += io.DeltaTime;
  shown_readout_group_.since += io.DeltaTime;

  ImGui::SetNextWindowPos(ImVec2(float(layout.width) - panel_w, 0.0f));
  ImGui::SetNextWindowSize(ImVec2(panel_w, float(layout.height)));
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                                 ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoSavedSettings |
                                 ImGuiWindowFlags_NoBringToFrontOnFocus |
                                 // Its background is the compositor's clear (UiGl::compose, the
                                 // same WindowBg colour): a blended quad over the panel's every
                                 // pixel cost a software rasterizer more than the clear does.
                                 ImGuiWindowFlags_NoBackground;
  if (ImGui::Begin("ponyhop##panel", nullptr, flags)) {
    // The title: the scene's name, large and wrapped (never cut off), its file below.
    const Scene& applied = sim_.applied();
    const bool big = io.Fonts->Fonts.Size > 1;
    if (big) ImGui::PushFont(io.Fonts->Fonts[1]);
    ImGui::PushTextWrapPos(0.0f);
    ImGui::TextUnformatted(applied.name.empty() ? "ponyhop" : applied.name.c_str());
    ImGui::PopTextWrapPos();
    if (big) ImGui::PopFont();
    ImGui::TextDisabled("ponyhop  %s", applied.path.c_str());
    ImGui::Separator();
    drawPlayback();
    drawLook();
    drawPresets();
    drawReadouts();
    drawSections();
  }
  ImGui::End();

  handleKeys();
  handleViewMouse(layout);
  sim_.applyEdits();
  const double panel_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  smoothInto(sim_.readouts().panel_ms, panel_ms);

  if (advance) sim_.advance(io.DeltaTime);
  updateCamera(layout, io.DeltaTime);
  // The pulled point follows the cursor while the camera or the body moves.
  if (drag_ == Drag::Pull && sim_.perturbation().active()) {
    const Eigen::Vector3d d = rayDirection(io.MousePos.x, io.MousePos.y, layout);
    const Eigen::Vector3d f = (camera_.target - camera_.eye).normalized();
    sim_.perturbation().target = camera_.eye + d * (grab_depth_ / std::max(d.dot(f), 1e-6));
  }
  drawViewOverlay(layout);
}

// A group is taken anew when its period has passed, on the first frame, on a run/pause, and when
// something the user did moved the simulation while paused (a step, an edit, a reset): so
// playback's figures change a few times a second and the user's own actions show at once. With
// no period, every time it is drawn (as it always was).
bool Panel::ShownFigures::due(const LiveSim& sim, double period) const {
  return period <= 0.0 || !valid || since >= period || sim.running() != running ||
         (!sim.running() && sim.changes() != changes);
}

void Panel::ShownFigures::taken(const LiveSim& sim) {
  valid = true;
  running = sim.running();
  changes = sim.changes();
  since = 0.0;
}

// ---------------------------------------------------------------------------------------------
// [SECTION] Panel: the parts of the panel

void Panel::drawPlayback() {
  const float w = ImGui::GetFontSize() * 4.6f;
  if (ImGui::Button(sim_.running() ? "Pause" : "Run", ImVec2(w, 0))) sim_.setRunning(!sim_.running());
  remember("run");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Run / pause the simulation (Space)");
  ImGui::SameLine();
  if (ImGui::Button("Step", ImVec2(w, 0))) {
    sim_.setRunning(false);
    sim_.stepOnce();
  }
  remember("step");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("One physics step of dt (Right arrow)");
  ImGui::SameLine();
  if (ImGui::Button("Reset", ImVec2(w, 0))) sim_.reset();
  remember("reset");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Start over at t = 0 with the current parameters (Backspace)");
  ImGui::SameLine();
  int speed = sim_.speedIndex();
  static const char* const kSpeedNames[] = {"1/16x", "1/8x", "1/4x", "1/2x", "1x", "1.5x", "2x", "3x", "4x"};
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x);
  if (ImGui::SliderInt("##speed", &speed, 0, int(kPlaybackSpeeds.size()) - 1, kSpeedNames[speed],
                       ImGuiSliderFlags_NoInput)) {
    sim_.setSpeedIndex(speed);
  }
  remember("speed");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Playback speed: slow motion to fast forward");

  const Scene& s = sim_.applied();
  if (shown_playback_.due(sim_, readout_refresh_)) {
    shown_playback_.taken(sim_);
    shown_time_ = sim_.simTime();
    shown_behind_ = sim_.fallingBehind();
    shown_rtf_ = sim_.achievedRealTimeFactor();
  }
  ImGui::Text("t = %.3f s", shown_time_);
  ImGui::SameLine();
  ImGui::TextDisabled("dt %.3g ms x %d substeps, %s", 1000.0 * s.physics.dt, s.physics.substeps,
                      std::string(enumName(s.physics.integrator)).c_str());
  if (shown_behind_) {
    ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.3f, 1.0f), "Behind: %.2fx real time (asked %.3gx)",
                       shown_rtf_ * sim_.speed(), sim_.speed());
  }
  if (!sim_.ok()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.45f, 0.4f, 1.0f));
    ImGui::TextWrapped("%s", sim_.stopMessage().c_str());
    ImGui::PopStyleColor();
    ImGui::TextWrapped("Paused. Change the parameter back, then Reset (Backspace).");
  }
  if (!sim_.error().empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.7f, 0.35f, 1.0f));
    ImGui::TextWrapped("Not applied: %s", sim_.error().c_str());
    ImGui::PopStyleColor();
  } else if (sim_.lastApply() != ApplyKind::None && sim_.lastApply() != ApplyKind::Live) {
    ImGui::TextDisabled("Last edit: %s (%.0f ms)", applyKindName(sim_.lastApply()), sim_.lastRebuildMs());
  }
}

void Panel::drawLook() {
  Scene& s = sim_.edited();
  if (!s.chain) return;
  if (!sectionHeader("Look", true)) return;
  ChainSection& c = *s.chain;
  const double g = s.physics.gravity.norm();
  const ChainLook look = chainLook(c, g);
  const float label_w = ImGui::GetFontSize() * 7.0f;
  ImGui::PushID("look");
  // One artist scale: label, slider with its value beside it, the physical value below it.
  const auto scale = [&](const char* id, const char* label, double value, double lo, double hi, const char* fmt,
                         bool log, const char* help, const std::string& physical, auto&& set) {
    ImGui::AlignTextToFramePadding();
    ImGui::TextUnformatted(label);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", help);
    ImGui::SameLine(label_w);
    char shown[48];
    std::snprintf(shown, sizeof shown, fmt, value);
    double v = value;
    ImGui::PushID(id);
    const SideSlider r = sideSlider("##s", ImGuiDataType_Double, &v, &lo, &hi, fmt,
                                    log ? ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_NoRoundToFormat : 0,
                                    ImGui::GetContentRegionAvail().x, shown);
    ImGui::PopID();
    rects_[std::string("look:") + id] = WidgetRect{r.min.x, r.min.y, r.max.x, r.max.y};
    if (r.changed && v != value) set(v);
    ImGui::SetCursorPosX(label_w);
    ImGui::TextDisabled("%s", physical.c_str());
  };
  char buf[160];
  std::snprintf(buf, sizeof buf, "= %d links x %.3g cm (a change restarts)", c.links, 100.0 * c.length);
  scale("length", "Length", look.length_cm, 1.0, 150.0, "%.1f cm", true, "The whole ponytail, root to tip", buf,
        [&](double v) { setLength(c, v); });
  std::snprintf(buf, sizeof buf, "= radius %.3g mm at the root", 1000.0 * c.radius);
  scale("thickness", "Thickness", look.thickness_mm, 1.0, 80.0, "%.1f mm", true, "Diameter at the root", buf,
        [&](double v) { setThickness(c, v); });
  std::snprintf(buf, sizeof buf, "= tip %.3g mm", 2000.0 * c.radius * c.taper);
  scale("taper", "Taper", c.taper, 0.05, 1.0, "%.2f", false, "Tip thickness over root thickness (1: even)", buf,
        [&](double v) { c.taper = v; });
  std::snprintf(buf, sizeof buf, "= %.3g g the first link (chain.mass)", 1000.0 * c.mass);
  scale("weight", "Weight", look.weight_g, 0.5, 500.0, "%.1f g", true, "Mass of the whole ponytail", buf,
        [&](double v) { setWeight(c, v); });
  // A root-to-tip ratio (chain.stiffness_tip, chain.damping_tip) under its root value.
  const auto tipScale = [&](const char* key, double& ratio, double at_tip, const char* unit, const char* what) {
    std::snprintf(buf, sizeof buf, "= tip %.3g %s (x%.3g of the root)", at_tip, unit, ratio);
    const std::string help =
        std::string("The tip joint's ") + what + " over the root's; the joints between follow a smooth curve";
    scale(key, "  toward tip", ratio, 0.01, 10.0, "x%.3g", true, help.c_str(), buf, [&](double v) { ratio = v; });
  };
  std::snprintf(buf, sizeof buf, "= %.3g N m/rad at the root; swings in %.2f s", c.stiffness, swingPeriod(c, g));
  scale("stiffness", "Stiffness", look.stiffness, 0.0, 1.5, "%.3f", false,
        "0: limp. 1: the root spring holds the ponytail straight out against its weight (stiffness^3 x M g d)", buf,
        [&](double v) { setStiffness(c, std::max(v, 0.0), g); });
  tipScale("stiffness_tip", c.stiffness_tip, jointStiffness(c, c.links - 1), "N m/rad", "stiffness");
  std::snprintf(buf, sizeof buf, "= damping %.3g N m s/rad (damping ratio %.3g)", c.damping, 1.0 - look.bounce);
  scale("bounce", "Bounce", look.bounce, 0.0, 1.0, "%.3f", false,
        "1: swings on and on. 0: settles without swinging (critically damped root swing)", buf,
        [&](double v) { setBounce(c, std::min(v, 1.0), g); });
  tipScale("damping_tip", c.damping_tip, jointDamping(c, c.links - 1), "N m s/rad", "damping");
  std::snprintf(buf, sizeof buf, "= drag %.3g N s/m^2", c.drag);
  scale("air", "Air", look.air, 0.0, 0.99, "%.2f", false,
        "Share of its speed the ponytail loses to the air in one second", buf,
        [&](double v) { setAir(c, std::clamp(v, 0.0, 0.99)); });
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted("Colour");
  ImGui::SameLine(label_w);
  float col[3] = {float(c.color.x()), float(c.color.y()), float(c.color.z())};
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x);
  if (ImGui::ColorEdit3("##colour", col, ImGuiColorEditFlags_Float)) c.color = Eigen::Vector3d(col[0], col[1], col[2]);
  remember("look:colour");
  // Root-to-tip curves of the joints' stiffness and damping, each over its root value.
  if (c.links > 1) {
    std::vector<float> ks, ds;
    for (int i = 0; i < c.links; ++i) {
      ks.push_back(c.stiffness > 0.0 ? float(jointStiffness(c, i) / c.stiffness) : 0.0f);
      ds.push_back(c.damping > 0.0 ? float(jointDamping(c, i) / c.damping) : 0.0f);
    }
    const float top =
        std::max({1.0f, *std::max_element(ks.begin(), ks.end()), *std::max_element(ds.begin(), ds.end())});
    const float w = 0.5f * (ImGui::GetContentRegionAvail().x - ImGui::GetStyle().ItemSpacing.x);
    ImGui::PlotLines("##kcurve", ks.data(), int(ks.size()), 0, "stiffness, root to tip", 0.0f, top * 1.05f,
                     ImVec2(w, 40));
    ImGui::SameLine();
    ImGui::PlotLines("##dcurve", ds.data(), int(ds.size()), 0, "damping, root to tip", 0.0f, top * 1.05f,
                     ImVec2(w, 40));
  }
  ImGui::PopID();
  ImGui::Spacing();
}

void Panel::drawReadouts() {
  if (!sectionHeader("Readouts", false)) return;
  if (shown_readout_group_.due(sim_, readout_refresh_)) {
    shown_readout_group_.taken(sim_);
    shown_readouts_ = sim_.readouts();
    shown_phase_ = sim_.hopperBody() >= 0 ? sim_.hopperPhase() : std::string();
    shown_contacts_.clear();
    if (const Collisions* c = sim_.runtime().collisions()) {
      // The contact solve's own account: sweeps of the last stage, and any solve that stopped at
      // its cap before its tolerance (physics/collisions.h).
      const CollisionStats& cs = c->stats();
      char buf[128];
      std::snprintf(buf, sizeof buf, "Contacts %d, PGS sweeps %d, stopped at the cap %ld", cs.active, cs.iterations,
                    cs.capped);
      shown_contacts_ = buf;
    }
  }
  const Readouts& r = shown_readouts_;
  const float plot_w = ImGui::GetContentRegionAvail().x;
  const auto plot = [&](const char* id, const History& h, const char* fmt, double scale) {
    char overlay[96];
    std::snprintf(overlay, sizeof overlay, fmt, h.last() * scale);
    const float lo = h.minValue(), hi = h.maxValue();
    const float pad = std::max(1e-12f, 0.1f * (hi - lo));
    ImGui::PlotLines(id, h.data(), h.count(), h.offset(), overlay, lo - pad, hi + pad, ImVec2(plot_w, 34.0f));
    remember(std::string("plot:") + id);
  };
  plot("##joint", r.joint_error, "max joint error %.3g mm", 1000.0);
  plot("##energy", r.energy, "energy %.4g J", 1.0);
  if (r.show_wall_clock) plot("##step", r.step_us, "physics step %.0f us", 1.0);
  if (sim_.hopperBody() >= 0) {
    plot("##height", r.hopper_height, "hopper height %.3f m", 1.0);
    plot("##speed", r.hopper_speed, "hopper speed %.2f m/s", 1.0);
    ImGui::Text("Hopper phase: %s", shown_phase_.c_str());
  }
  if (!shown_contacts_.empty()) ImGui::TextUnformatted(shown_contacts_.c_str());
  if (r.show_wall_clock) {
    if (r.frame_ms > 0.0)  // the window's (a headless frame has no swap)
      ImGui::TextDisabled("Frame: %.1f fps, %.1f ms: physics %.2f  panel %.2f  render %.2f  compose %.2f",
                          1000.0 / r.frame_ms, r.frame_ms, r.physics_ms, r.panel_ms, r.render_ms, r.compose_ms);
    else
      ImGui::TextDisabled("Frame: physics %.2f  render %.2f  panel %.2f ms", r.physics_ms, r.render_ms, r.panel_ms);
    ImGui::TextDisabled("View: %s  (shadow %.1f  main %.1f  AA %.1f ms)", r.view_draft ? "draft, moving" : "final",
                        r.shadow_ms, r.main_ms, r.aa_ms);
  } else {
    ImGui::TextDisabled("View: %s", r.view_draft ? "draft, moving" : "final");
  }
}

void Panel::drawPresets() {
  if (!sectionHeader("Presets", true)) return;
  // The shipped presets (assets/presets/NAME.json): one click lays one over the edited scene.
  if (sim_.edited().chain) {
    const float w = ImGui::GetFontSize() * 4.4f, gap = ImGui::GetStyle().ItemSpacing.x;
    const int per_row = std::max(1, int((ImGui::GetContentRegionAvail().x + gap) / (w + gap)));
    int i = 0;
    for (const std::string& name : presetNames()) {
      if (i++ % per_row != 0) ImGui::SameLine();
      if (ImGui::Button(name.c_str(), ImVec2(w, 0))) {
        try {
          sim_.edited() = applyPreset(sim_.edited(), name);
          preset_error_ = false;
          preset_message_ = "Preset " + name + " applied (Save keeps it)";
        } catch (const InputError& e) {
          preset_error_ = true;
          preset_message_ = e.what();
        }
      }
      remember("preset:" + name);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", presetSummary(name).c_str());
    }
  }
  char buf[512];
  std::snprintf(buf, sizeof buf, "%s", preset_path_.c_str());
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x);
  if (ImGui::InputText("##path", buf, sizeof buf)) preset_path_ = buf;
  remember("path");
  const float w = 0.5f * (ImGui::GetContentRegionAvail().x - ImGui::GetStyle().ItemSpacing.x);
  if (ImGui::Button("Save", ImVec2(w, 0))) {
    preset_error_ = !sim_.save(preset_path_);
    preset_message_ = preset_error_ ? sim_.error() : "Saved " + preset_path_;
  }
  remember("save");
  ImGui::SameLine();
  if (ImGui::Button("Load", ImVec2(w, 0))) {
    preset_error_ = !sim_.load(preset_path_);
    preset_message_ = preset_error_ ? sim_.error() : "Loaded " + preset_path_;
    if (!preset_error_) free_view_ = false;
  }
  remember("load");
  if (!preset_message_.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text,
                          preset_error_ ? ImVec4(1.0f, 0.5f, 0.4f, 1.0f) : ImVec4(0.6f, 0.85f, 0.6f, 1.0f));
    ImGui::TextWrapped("%s", preset_message_.c_str());
    ImGui::PopStyleColor();
  }
}

void Panel::drawSections() {
  Scene& s = sim_.edited();
  // Artists first: what moves, then how it is simulated, then how it looks.
  const auto section = [&](const char* field, const char* title, bool open, std::vector<std::string> skip = {}) {
    SectionVisitor v(*this, field, title, open, {}, std::move(skip));
    s.reflect(v);
  };
  section("chain", "Ponytail: every field", false, {"hair"});
  {
    NestedSection v(*this, "chain", "hair", "Hair", false);  // how it is drawn: strands, highlight, tie
    s.reflect(v);
  }
  for (size_t i = 0; i < s.chains.size(); ++i) {
    // Each listed chain: every field (an edit rebuilds the scene: the list applies as a whole).
    const std::string key = "chains." + std::to_string(i);
    const std::string title = "Chain " + key + ": every field";
    if (sectionHeader(title.c_str(), false)) {
      ImGui::PushID(key.c_str());
      FieldWidgets w(*this, key + ".");
      s.chains[i].reflect(w);
      ImGui::PopID();
      ImGui::Spacing();
    }
  }
  section("head", "Head", false);
  section("anchor", "Anchor", false);
  {
    NestedSection v(*this, "hopper", "command", "Hopper commands", true);
    s.reflect(v);
  }
  section("hopper", "Hopper", false, {"command"});
  section("collision", "Collisions", false);
  section("physics", "Physics", false);
  if (sectionHeader("Camera", false)) {
    drawCameraTools();
    FieldWidgets w(*this, "camera.");
    s.camera.reflect(w);
    ImGui::Spacing();
  }
  section("light", "Lighting", false);
  section("render", "Render", false);
  drawGoals();
  if (sectionHeader("Scene", false)) {
    FieldWidgets w(*this, "", {"name", "duration"});
    s.reflect(w);
  }
}

// The goals (docs/GOALS.md, "In the panel"): the markers' switch (render.goals), each goal's time,
// point and position as drag widgets (the marker in the view moves as one drags: goals apply
// live), its residual from the last solve, the guide's on/off, and Solve, which runs `ponyhop
// solve`'s defaults on the applied scene in a thread and, when done, writes the guide into the
// scene (which restarts the run with it).
void Panel::drawGoals() {
  pollSolve();
  Scene& s = sim_.edited();
  if (!sectionHeader("Goals", false)) return;
  ImGui::Checkbox("Markers in the view", &s.render.goals);
  remember("goals:markers");
  if (s.guide) {
    ImGui::SameLine();
    ImGui::Checkbox("Guide on", &s.guide->enabled);
    remember("goals:guide");
  }
  if (s.goals.empty()) ImGui::TextDisabled("No goals (add them in the scene file: docs/GOALS.md)");
  const double now = sim_.simTime();
  for (size_t i = 0; i < s.goals.size(); ++i) {
    Goal& g = s.goals[i];
    const std::string key = "goals." + std::to_string(i);
    std::string residual = "not solved";
    if (i < solved_outcomes_.size() && i < solved_goals_.size()) {
      const Goal& was = solved_goals_[i];
      const bool same = was.t == g.t && was.position == g.position && was.point == g.point && was.frame == g.frame;
      char text[96];
      std::snprintf(text, sizeof text, "%.2f mm%s%s", 1e3 * solved_outcomes_[i].error,
                    solved_outcomes_[i].met ? " (met)" : " (not met)", same ? "" : ", edited since");
      residual = text;
    }
    const bool near = std::abs(now - g.t) <= SceneDraw::kGoalNear;
    ImGui::PushID(key.c_str());
    const std::string title = "Goal " + std::to_string(i) + ": " + g.point + " at " + std::to_string(g.t).substr(0, 5) +
                              " s, residual " + residual;
    if (near) ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.45f, 0.95f, 1.0f));
    ImGui::TextUnformatted(title.c_str());
    if (near) ImGui::PopStyleColor();
    remember(key);
    FieldWidgets w(*this, key + ".", {"t", "position", "frame"});
    g.reflect(w);
    ImGui::PopID();
  }
  ImGui::BeginDisabled(solving() || s.goals.empty());
  if (ImGui::Button(solving() ? "Solving..." : "Solve")) {
    const Scene scene = sim_.applied();
    solve_started_ = std::chrono::steady_clock::now();
    solve_ = std::async(std::launch::async, [scene] { return solveGoals(scene, &assimpAssets()); });
    solve_status_ = "solving (the scene as it was at the press)...";
    solved_goals_ = scene.goals;
    solved_outcomes_.clear();
  }
  ImGui::EndDisabled();
  remember("goals:solve");
  if (solving()) {
    ImGui::SameLine();
    const double s_elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - solve_started_).count();
    ImGui::Text("%.0f s", s_elapsed);
  }
  if (!solve_status_.empty()) {
    ImGui::PushTextWrapPos(0.0f);
    ImGui::TextDisabled("%s", solve_status_.c_str());
    ImGui::PopTextWrapPos();
  }
}

void Panel::pollSolve() {
  if (!solve_.valid() || solve_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  try {
    GoalSolveReport r = solve_.get();
    solved_outcomes_ = r.goals;
    sim_.edited().guide = r.guide;
    sim_.edited().guide->enabled = true;
    int met = 0;
    for (const GoalOutcome& o : r.goals) met += o.met;
    char text[160];
    std::snprintf(text, sizeof text, "solved: %d of %zu goals met, %d iterations, effort %.3g N^2 m^2 s, %.1f s CPU",
                  met, r.goals.size(), r.iterations, r.effort, r.cpu_seconds);
    solve_status_ = text;
  } catch (const std::exception& e) {
    solve_status_ = std::string("solve failed: ") + e.what();
  }
}

void Panel::drawCameraTools() {
  if (free_view_) {
    ImGui::TextDisabled("Mouse view (the scene camera is unchanged)");
    if (ImGui::Button("Back to scene camera")) free_view_ = false;
    remember("camera:scene");
    ImGui::SameLine();
    if (ImGui::Button("Store view")) {
      CameraParams& c = sim_.edited().camera;
      c.mode = CameraMode::Fixed;
      c.position = camera_.eye;
      c.target = camera_.target;
      free_view_ = false;
    }
    remember("camera:store");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Make this view the scene's fixed camera (saved with the preset)");
  } else {
    ImGui::TextDisabled("Drag the view to orbit; right-drag pans; wheel zooms");
  }
}

// ---------------------------------------------------------------------------------------------
// [SECTION] Panel: keys, mouse, the camera and the view's overlay

void Panel::handleKeys() {
  ImGuiIO& io = ImGui::GetIO();
  if (io.WantTextInput) return;
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Space), false)) sim_.setRunning(!sim_.running());
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Backspace), false)) sim_.reset();
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_RightArrow), true)) {
    sim_.setRunning(false);
    sim_.stepOnce();
  }
}

Eigen::Vector3d Panel::rayDirection(float mx, float my, const PanelLayout& layout) const {
  const double w = std::max(layout.sceneWidth(), 1), h = std::max(layout.height, 1);
  const Eigen::Vector3d f = (camera_.target - camera_.eye).normalized();
  const Eigen::Vector3d r = f.cross(camera_.up).normalized();
  const Eigen::Vector3d u = r.cross(f);
  const double th = std::tan(0.5 * camera_.fov * M_PI / 180.0);
  const double x = (2.0 * (mx + 0.5) / w - 1.0) * th * (w / h);
  const double y = (1.0 - 2.0 * (my + 0.5) / h) * th;
  return (f + x * r + y * u).normalized();
}

bool Panel::pick(float mx, float my, const PanelLayout& layout) {
  const World& world = sim_.runtime().world();
  const Eigen::Vector3d o = camera_.eye, d = rayDirection(mx, my, layout);
  // A few pixels of slack so that a thin strand of hair can be caught.
  const double px = 2.0 * std::tan(0.5 * camera_.fov * M_PI / 180.0) / std::max(layout.height, 1);
  double best = INFINITY;
  int body = -1;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  std::vector<bool> in_chain(size_t(world.bodyCount()), false);
  for (const Chain& chain : sim_.runtime().chains()) {
    const Chain* c = &chain;
    for (size_t i = 0; i < c->links.size(); ++i) {
      in_chain[size_t(c->links[i])] = true;
      double s = 0.0;
      const Eigen::Vector3d q = closestOnSegment(o, d, c->top(world, int(i)), c->bottom(world, int(i)), s);
      const double dist = (o + s * d - q).norm();
      if (dist <= c->radii[i] * 1.2 + 6.0 * px * s && s < best) {
        best = s;
        body = c->links[i];
        point = q;
      }
    }
  }
  for (int i = 0; i < world.bodyCount(); ++i) {
    const RigidBody& b = world.body(i);
    if (!b.isDynamic() || in_chain[size_t(i)]) continue;
    // Other bodies (the hopper's): the sphere of the same largest inertia, as a pick volume.
    const double radius = std::clamp(std::sqrt(2.5 * b.inertia.maxCoeff() / b.mass), 0.02, 1.0);
    const double s = std::max(0.0, (b.x - o).dot(d));
    const Eigen::Vector3d p = o + s * d;
    if ((p - b.x).norm() <= radius && s < best) {
      best = s;
      body = i;
      point = p;
    }
  }
  if (body < 0) return false;
  PerturbationTarget& t = sim_.perturbation();
  const RigidBody& b = world.body(body);
  t.body = body;
  t.local_point = b.q.conjugate() * (point - b.x);
  t.target = point;
  grab_depth_ = (point - camera_.eye).dot((camera_.target - camera_.eye).normalized());
  return true;
}

void Panel::handleViewMouse(const PanelLayout& layout) {
  ImGuiIO& io = ImGui::GetIO();
  const float mx = io.MousePos.x, my = io.MousePos.y;
  const bool in_view = mx >= 0 && my >= 0 && mx < layout.sceneWidth() && my < layout.height;
  const auto enterFreeView = [&] {
    if (free_view_) return;
    const Eigen::Vector3d d = camera_.eye - camera_.target;
    distance_ = std::max(d.norm(), 1e-3);
    azimuth_ = std::atan2(d.y(), d.x());
    elevation_ = std::asin(std::clamp(d.z() / distance_, -1.0, 1.0));
    view_target_ = camera_.target;
    if (sim_.applied().camera.mode == CameraMode::Follow) view_target_ -= sim_.followPoint();
    free_view_ = true;
  };
  if (drag_ == Drag::None) {
    if (io.WantCaptureMouse || !in_view) return;
    if (ImGui::IsMouseClicked(0)) {
      if (!io.KeyCtrl && pick(mx, my, layout)) {
        drag_ = Drag::Pull;
      } else {
        enterFreeView();
        drag_ = io.KeyCtrl ? Drag::Pan : Drag::Orbit;
      }
    } else if (ImGui::IsMouseClicked(1) || ImGui::IsMouseClicked(2)) {
      enterFreeView();
      drag_ = Drag::Pan;
    }
    if (io.MouseWheel != 0.0f) {
      enterFreeView();
      distance_ = std::clamp(distance_ * std::pow(0.88, double(io.MouseWheel)), 0.02, 500.0);
    }
    return;
  }
  const double dx = io.MouseDelta.x, dy = io.MouseDelta.y;
  const bool any_down = io.MouseDown[0] || io.MouseDown[1] || io.MouseDown[2];
  switch (drag_) {
    case Drag::Orbit:
      azimuth_ -= 0.008 * dx;
      elevation_ = std::clamp(elevation_ + 0.008 * dy, -1.5, 1.5);
      if (!io.MouseDown[0]) drag_ = Drag::None;
      break;
    case Drag::Pan: {
      const Eigen::Vector3d f = (camera_.target - camera_.eye).normalized();
      const Eigen::Vector3d r = f.cross(camera_.up).normalized();
      const Eigen::Vector3d u = r.cross(f);
      const double scale = 2.0 * distance_ * std::tan(0.5 * camera_.fov * M_PI / 180.0) / std::max(layout.height, 1);
      view_target_ += (-dx * r + dy * u) * scale;
      if (!any_down) drag_ = Drag::None;
      break;
    }
    case Drag::Pull:
      if (!io.MouseDown[0]) {
        sim_.perturbation().body = -1;
        drag_ = Drag::None;
      }
      break;
    case Drag::None:
      break;
  }
}

void Panel::updateCamera(const PanelLayout& layout, double dt) {
  (void)layout;
  const Scene& s = sim_.applied();
  const double t = sim_.simTime();
  const double step = t - last_cam_time_;
  last_cam_time_ = t;
  if (step < 0.0) follow_.reset();  // a reset or restart: snap to the body again
  Camera scene_cam;
  if (s.camera.mode == CameraMode::Follow) {
    scene_cam = follow_.update(s.camera, t, sim_.followPoint(), std::max(step, 0.0));
  } else {
    scene_cam = cameraAt(s.camera, t);
  }
  (void)dt;
  if (!free_view_) {
    camera_ = scene_cam;
    return;
  }
  Eigen::Vector3d target = view_target_;
  if (s.camera.mode == CameraMode::Follow) target += sim_.followPoint();
  const Eigen::Vector3d dir(std::cos(elevation_) * std::cos(azimuth_), std::cos(elevation_) * std::sin(azimuth_),
                            std::sin(elevation_));
  camera_ = scene_cam;
  camera_.target = target;
  camera_.eye = target + distance_ * dir;
  camera_.up = Eigen::Vector3d::UnitZ();
}

void Panel::drawViewOverlay(const PanelLayout& layout) {
  ImDrawList* dl = ImGui::GetBackgroundDrawList();
  const auto text = [&](float x, float y, ImU32 color, const char* s) {
    dl->AddText(ImVec2(x + 1, y + 1), IM_COL32(0, 0, 0, 140), s);
    dl->AddText(ImVec2(x, y), color, s);
  };
  char buf[160];
  const char* state = !sim_.ok() ? "stopped" : (sim_.running() ? "running" : "paused");
  std::snprintf(buf, sizeof buf, "t = %.2f s   %s   %s", sim_.simTime(), state,
                sim_.speedIndex() == kRealTimeSpeedIndex ? "1x" : (std::string(number(sim_.speed())) + "x").c_str());
  text(12.0f, 10.0f, IM_COL32(255, 255, 255, 235), buf);
  if (sim_.fallingBehind()) {
    std::snprintf(buf, sizeof buf, "behind: %.2fx real time", sim_.achievedRealTimeFactor() * sim_.speed());
    text(12.0f, 30.0f, IM_COL32(255, 200, 90, 255), buf);
  }
  if (!sim_.ok())
    text(12.0f, 30.0f, IM_COL32(255, 110, 100, 255), "Simulation stopped: see the panel. Backspace resets.");
  text(12.0f, float(layout.height) - 26.0f, IM_COL32(255, 255, 255, 170),
       "drag: orbit   right-drag: pan   wheel: zoom   drag hair/body: pull   Space: run/pause");
}

}  // namespace ponyhop
