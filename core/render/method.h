// A render method as one unit (issue "One copy of the physics, a method as one unit"): its name,
// what --spp sets, the setting groups it reads, its output layers (one table, compare Falcor's
// kOutputChannels), how it renders a frame and how it traces a pixel. FrameRenderer, the pixel
// trace, the CLI (--method, --spp, help) and the workbench's method menu read this registry
// and nothing else; adding a method is its own file plus one register_render_method call.
//
// The built-in methods (render/method.cpp) hold the ids of the RenderMethod enum in order;
// register_render_method gives a new method the next id. Registration is not thread-safe: do
// it before rendering starts (static initialisation or main / a test's start).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/byte_stream.h"
#include "base/job.h"
#include "image/layers.h"
#include "render/gbuffer.h"

namespace freqlab {

enum class RenderMethod;
struct RenderConfig;
struct FrameResult;
struct ShadingPoint;
struct SurfaceHit;
struct ReconstructionRecord;
struct RadiancePoint;
class RayScene;
class EnvBandwidthHierarchy;
class ShadingMemo;
struct CameraRayGenerator;
enum class SampleSequence;

// What a method keeps across the frames of one FrameRenderer (method A's cache).
struct MethodState {
    virtual ~MethodState() = default;
    // The state exactly, for a checkpoint (render/frame_checkpoint.h); decode throws Error
    // naming `source` on bytes that are not a whole state.
    virtual void encode(ByteWriter& w) const = 0;
    virtual void decode(ByteReader& r, const std::string& source) = 0;
};

// One frame's inputs: the scene at the frame's time, its G-buffer, and the result whose
// layers already hold the G-buffer's.
struct MethodContext {
    const RayScene& rays;
    const GBuffer& gbuffer;
    int frame;
    const RenderConfig& config;
    const EnvBandwidthHierarchy* bandwidth;       // when the method asks for it (and a map exists)
    MethodState* state;                           // its make_state()'s, else null
    bool keep_details;                            // FrameRenderer::keep_cache_details
    ReconstructionRecord* reconstruction_record;  // FrameRenderer::record_reconstruction
    FrameResult& result;
    Progress& progress;
    // FrameRenderer::set_preview_sink: methods that can show a first image hand it here.
    const std::function<void(LayerSet&&)>* preview = nullptr;
    // FrameRenderer::set_shading_memo: methods that shade radiance points recall them there.
    ShadingMemo* memo = nullptr;
};
struct MethodOutput {
    long rays = 0;       // beyond the G-buffer's
    long nonfinite = 0;  // estimates guarded against NaN / Inf
    // Merged into the frame's stats; a "stages" object into its stages (ms).
    nlohmann::json stats = nlohmann::json::object();
};

// A pixel of a rendered frame, with the hit and shading point the render saw there.
struct PixelTraceContext {
    const RayScene& rays;
    const RenderConfig& config;
    const FrameResult& result;
    int x, y;
    const CameraRayGenerator& camera;
    const SurfaceHit& hit;
    const ShadingPoint& point;
    const EnvBandwidthHierarchy* bandwidth;
    size_t max_samples;
    RadiancePoint* radiance_point;  // method points: receives the pixel's radiance point
};
using TraceLines = std::vector<std::string>;

// A layer a method writes beyond the G-buffer's (color, albedo, normal, position, depth,
// object); FrameRenderer checks each is there, with its kind, after every frame.
struct LayerDeclaration {
    std::string name;
    LayerKind kind = LayerKind::Continuous;
};

struct RenderMethodInfo {
    std::string name;
    std::string summary;  // one line, for help texts and tooltips
    // The setting groups the method reads ("frame", "shading", "mis", ...).
    std::vector<std::string> setting_groups;
    // The setting --spp sets; empty: --spp is refused with spp_refusal.
    std::string spp_setting;
    std::string spp_refusal;
    bool antialiased_gbuffer = false;  // the G-buffer's AA rays are cast (its colour shown)
    bool env_bandwidth = false;        // needs method A's environment bandwidth hierarchy
    bool stateful = false;             // frames must come in order (state across frames)
    std::vector<LayerDeclaration> layers;
    // The samples per pixel its estimate takes (stats "spp"); null: 0.
    std::function<int(const RenderConfig&)> spp;
    std::function<SampleSequence(const RenderConfig&)> sequence;  // null: independent
    std::function<std::unique_ptr<MethodState>()> make_state;     // null: stateless
    // Null: the G-buffer is the result (nothing is shaded, nothing to trace).
    std::function<MethodOutput(MethodContext&)> render;
    // The method's part of a pixel trace, after the camera ray, hit and shading point (the
    // numbers of the render: same keys, same estimator). Null: "no per-pixel trace".
    std::function<void(const PixelTraceContext&, TraceLines&)> trace;
};

// Registers a method; throws Error when the name is taken or empty. Returns its id.
RenderMethod register_render_method(RenderMethodInfo info);
// Throws Error for an id nothing registered.
const RenderMethodInfo& render_method_info(RenderMethod method);
std::vector<std::string> render_method_names();  // in id order
// "gbuffer|mis|..." (help texts) with `separator` between the names.
std::string render_method_list(const std::string& separator = "|");
// Throws Error naming --method and listing the methods.
RenderMethod parse_render_method(const std::string& name);

}  // namespace freqlab
