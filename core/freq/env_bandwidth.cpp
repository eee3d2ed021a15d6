#include "freq/env_bandwidth.h"

#include <fftw3.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <boost/math/tools/roots.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstring>
#include <mutex>

#include "base/error.h"
#include "base/file_io.h"
#include "base/hash.h"
#include "freq/brdf_footprint.h"
#include "image/layers.h"
#include "scene/light.h"

namespace freqlab {

namespace {

constexpr const char* kMagic = "freqlab-env-bandwidth";

// FFTW's planner is not thread-safe; execution on fresh arrays of the same alignment is.
std::mutex& fftw_planner_mutex() {
    static std::mutex m;
    return m;
}

struct FftPlan {
    int P;
    fftw_plan plan;
    explicit FftPlan(int p) : P(p) {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        double* in = fftw_alloc_real(size_t(P) * P);
        fftw_complex* out = fftw_alloc_complex(size_t(P) * (P / 2 + 1));
        plan = fftw_plan_dft_r2c_2d(P, P, in, out, FFTW_ESTIMATE);
        fftw_free(in);
        fftw_free(out);
    }
    ~FftPlan() {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        fftw_destroy_plan(plan);
    }
    FftPlan(const FftPlan&) = delete;
    FftPlan& operator=(const FftPlan&) = delete;
};

struct FftBuffers {
    int P = 0;
    double* in = nullptr;
    fftw_complex* out = nullptr;
    void ensure(int p) {
        if (P == p) return;
        release();
        P = p;
        in = fftw_alloc_real(size_t(P) * P);
        out = fftw_alloc_complex(size_t(P) * (P / 2 + 1));
    }
    void release() {
        if (in) fftw_free(in);
        if (out) fftw_free(out);
        in = nullptr;
        out = nullptr;
    }
    FftBuffers() = default;
    FftBuffers(const FftBuffers&) {}  // thread-local copies start empty
    FftBuffers& operator=(const FftBuffers&) = delete;
    ~FftBuffers() { release(); }
};

// |F|^2 on the half plane (rows ky = 0..P-1, columns kx = 0..P/2) from FFTW's output.
void energy_from_fft(const fftw_complex* out, int P, std::vector<double>& energy) {
    const int half = P / 2 + 1;
    energy.resize(size_t(P) * half);
    for (size_t i = 0; i < energy.size(); ++i)
        energy[i] = out[i][0] * out[i][0] + out[i][1] * out[i][1];
}

// The percentile radius (in ring units 1 / (P h)) from half-plane energies; columns 1..P/2-1
// stand for their conjugate twins too.
double percentile_radius(const std::vector<double>& energy, int P, double percentile) {
    const int half = P / 2 + 1;
    const int rings = int(std::ceil(std::sqrt(2.0) * P / 2)) + 2;
    std::vector<double> ring(size_t(rings), 0.0);
    double total = 0.0;
    for (int ky = 0; ky < P; ++ky) {
        const int fy = ky <= P / 2 ? ky : ky - P;
        for (int kx = 0; kx < half; ++kx) {
            const double e =
                energy[size_t(ky) * half + size_t(kx)] * ((kx == 0 || kx == P / 2) ? 1.0 : 2.0);
            const int r = int(std::lround(std::sqrt(double(kx * kx + fy * fy))));
            ring[size_t(r)] += e;
            total += e;
        }
    }
    if (!(total > 0)) return 0.0;
    double cumulative = 0.0;
    for (int r = 0; r < rings; ++r) {
        const double next = cumulative + ring[size_t(r)];
        if (next >= percentile * total) {
            // Ring r covers radii [r - 1/2, r + 1/2): linear within it.
            const double f =
                ring[size_t(r)] > 0 ? (percentile * total - cumulative) / ring[size_t(r)] : 0.0;
            return std::max(0.0, r - 0.5 + f);
        }
        cumulative = next;
    }
    return rings - 1;
}

// Footprint radius atan(3 sigma(e)) = r: the window exponent of a level (bisection on log e).
double window_exponent(double radius) {
    if (radius >= 0.5 * kPiD - 1e-9) return 1.0;
    auto f = [&](double log_e) {
        const double e = std::exp(log_e);
        return std::atan(3.0 * std::sqrt(phong_variance(e))) - radius;
    };
    boost::math::tools::eps_tolerance<double> tol(40);
    std::uintmax_t iterations = 200;
    const auto [a, b] =
        boost::math::tools::bisect(f, std::log(3.0 + 1e-6), std::log(1e9), tol, iterations);
    return std::exp(0.5 * (a + b));
}

vec2 uv_of(const vec3& d, float rotation_deg) {
    const float theta = std::atan2(std::sqrt(d.x * d.x + d.y * d.y), d.z);
    float phi = std::atan2(d.y, d.x) - glm::radians(rotation_deg);
    phi -= 2.0f * float(kPiD) * std::floor(phi / (2.0f * float(kPiD)));
    return vec2(phi / (2.0f * float(kPiD)), theta / float(kPiD));
}

vec3 node_direction(int i, int j, int W, int H, float rotation_deg) {
    const double phi = 2.0 * kPiD * (i + 0.5) / W + glm::radians(double(rotation_deg));
    const double theta = kPiD * (j + 0.5) / H;
    return vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                float(std::cos(theta)));
}

double bilinear(const std::vector<float>& grid, int W, int H, vec2 uv) {
    const double x = uv.x * W - 0.5, y = std::clamp(double(uv.y) * H - 0.5, 0.0, H - 1.0);
    const int x0 = int(std::floor(x)), y0 = std::min(int(y), H - 2 < 0 ? 0 : H - 2);
    const double fx = x - x0, fy = H > 1 ? y - y0 : 0.0;
    auto at = [&](int xi, int yi) {
        xi = ((xi % W) + W) % W;
        yi = std::clamp(yi, 0, H - 1);
        return double(grid[size_t(yi) * W + size_t(xi)]);
    };
    return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
           fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

}  // namespace

std::vector<double> patch_spectrum(const std::vector<double>& patch, int P, bool direct_dft) {
    const int half = P / 2 + 1;
    std::vector<double> energy;
    if (direct_dft) {
        energy.assign(size_t(P) * half, 0.0);
        for (int ky = 0; ky < P; ++ky)
            for (int kx = 0; kx < half; ++kx) {
                std::complex<double> sum = 0.0;
                for (int y = 0; y < P; ++y)
                    for (int x = 0; x < P; ++x)
                        sum += patch[size_t(y) * P + size_t(x)] *
                               std::polar(1.0, -2.0 * kPiD * (double(kx) * x + double(ky) * y) / P);
                energy[size_t(ky) * half + size_t(kx)] = std::norm(sum);
            }
        return energy;
    }
    FftPlan plan(P);
    FftBuffers buffers;
    buffers.ensure(P);
    std::copy(patch.begin(), patch.end(), buffers.in);
    fftw_execute_dft_r2c(plan.plan, buffers.in, buffers.out);
    energy_from_fft(buffers.out, P, energy);
    return energy;
}

double patch_bandwidth(const std::vector<double>& patch, int P, double spacing, double percentile,
                       bool direct_dft) {
    return percentile_radius(patch_spectrum(patch, P, direct_dft), P, percentile) / (P * spacing);
}

EnvBandwidthHierarchy EnvBandwidthHierarchy::build(const EnvironmentMap& env) {
    EnvBandwidthHierarchy h;
    const RgbImage& image = env.image();
    h.env_width_ = image.width;
    h.rotation_deg_ = env.rotation_deg();
    const double texel = 2.0 * kPiD / image.width;
    h.nyquist_ = 1.0 / (2.0 * texel);
    for (double radius = 0.5 * kPiD; 2.0 * radius >= 16.0 * texel; radius *= 0.5) {
        Level level;
        level.radius = radius;
        level.exponent = window_exponent(radius);
        int P = 16;
        while (P < 256 && P < 2.0 * radius / texel) P *= 2;
        level.patch_size = P;
        level.height = std::max(4, int(std::ceil(kPiD / (0.5 * radius))));
        level.width = 2 * level.height;
        h.levels_.push_back(level);
    }
    tbb::enumerable_thread_specific<FftBuffers> buffers;
    tbb::enumerable_thread_specific<std::vector<double>> energies;
    for (Level& level : h.levels_) {
        const int P = level.patch_size, W = level.width, H = level.height;
        const double spacing = 2.0 * level.radius / P;
        FftPlan plan(P);
        level.bandwidth.assign(size_t(W) * H, 0.0f);
        // The patch's layout is the same about every node: offsets (cos, sin cos, sin sin) of
        // each sample from mu, and the window, computed once per level.
        struct PatchSample {
            double along, tangent, binormal, window;
        };
        std::vector<PatchSample> layout(size_t(P) * P);
        for (int y = 0; y < P; ++y)
            for (int x = 0; x < P; ++x) {
                const double u = (x + 0.5 - 0.5 * P) * spacing, v = (y + 0.5 - 0.5 * P) * spacing;
                const double theta = std::sqrt(u * u + v * v), phi = std::atan2(v, u);
                layout[size_t(y) * P + size_t(x)] = {
                    std::cos(theta), std::sin(theta) * std::cos(phi),
                    std::sin(theta) * std::sin(phi),
                    theta < 0.5 * kPiD ? std::pow(std::cos(theta), level.exponent) : 0.0};
            }
        std::vector<vec3> directions(size_t(W) * H);
        for (int node = 0; node < W * H; ++node)
            directions[size_t(node)] = node_direction(node % W, node / W, W, H, h.rotation_deg_);
        tbb::parallel_for(0, W * H, [&](int node) {
            const vec3 mu = directions[size_t(node)];
            glm::dvec3 t, b;
            const glm::dvec3 m(mu);
            t = glm::normalize(std::fabs(m.z) < 0.9 ? glm::cross(glm::dvec3(0, 0, 1), m)
                                                    : glm::cross(glm::dvec3(1, 0, 0), m));
            b = glm::cross(m, t);
            FftBuffers& buf = buffers.local();
            buf.ensure(P);
            double weight_sum = 0.0, weighted = 0.0;
            for (size_t k = 0; k < layout.size(); ++k) {
                const PatchSample& s = layout[k];
                double value = 0.0;
                if (s.window > 0) {
                    const glm::dvec3 d = s.along * m + s.tangent * t + s.binormal * b;
                    value = luminance(env.eval_smooth(vec3(d)));
                }
                buf.in[k] = value;
                weight_sum += s.window;
                weighted += s.window * value;
            }
            const double mean = weight_sum > 0 ? weighted / weight_sum : 0.0;
            double ac = 0.0, dc = 0.0;
            for (size_t k = 0; k < layout.size(); ++k) {
                const double w = layout[k].window;
                buf.in[k] = w * (buf.in[k] - mean);
                ac += buf.in[k] * buf.in[k];
                dc += w * w * mean * mean;
            }
            // A constant patch leaves only rounding: the lowest band, not a random percentile.
            if (!(ac > 1e-10 * dc)) {
                level.bandwidth[size_t(node)] = 0.0f;
                return;
            }
            fftw_execute_dft_r2c(plan.plan, buf.in, buf.out);
            std::vector<double>& energy = energies.local();
            energy_from_fft(buf.out, P, energy);
            const double bw = percentile_radius(energy, P, 0.95) / (P * spacing);
            level.bandwidth[size_t(node)] = float(std::min(bw, h.nyquist_));
        });
        // The footprint maximum: nodes within `radius` of each node.
        level.maximum = level.bandwidth;
        tbb::parallel_for(0, W * H, [&](int node) {
            const int j = node / W;
            const vec3 mu = directions[size_t(node)];
            const float cos_r = float(std::cos(level.radius));
            float best = level.bandwidth[size_t(node)];
            const int dj = int(std::ceil(level.radius / (kPiD / H))) + 1;
            for (int jj = std::max(0, j - dj); jj <= std::min(H - 1, j + dj); ++jj)
                for (int ii = 0; ii < W; ++ii) {
                    const size_t other = size_t(jj) * W + size_t(ii);
                    if (glm::dot(mu, directions[other]) >= cos_r)
                        best = std::max(best, level.bandwidth[other]);
                }
            level.maximum[size_t(node)] = best;
        });
    }
    return h;
}

double EnvBandwidthHierarchy::level_value(int l, const vec3& direction) const {
    const Level& level = levels_[size_t(l)];
    return bilinear(level.maximum, level.width, level.height, uv_of(direction, rotation_deg_));
}

double EnvBandwidthHierarchy::query(const vec3& direction, double radius) const {
    if (levels_.empty()) return nyquist_;
    const double finest = levels_.back().radius;
    if (radius < finest) return nyquist_;
    const double lambda =
        std::clamp(std::log2(0.5 * kPiD / radius), 0.0, double(levels_.size() - 1));
    const int l0 = std::min(int(lambda), int(levels_.size()) - 1),
              l1 = std::min(l0 + 1, int(levels_.size()) - 1);
    const double f = lambda - l0;
    const double b0 = level_value(l0, direction);
    return f > 0 ? (1 - f) * b0 + f * level_value(l1, direction) : b0;
}

void EnvBandwidthHierarchy::save(const std::filesystem::path& path) const {
    nlohmann::json header = {{"version", kFormatVersion},
                             {"env_width", env_width_},
                             {"rotation_deg", rotation_deg_},
                             {"nyquist", nyquist_},
                             {"content_hash", std::to_string(content_hash_)}};
    std::string payload;
    for (const Level& l : levels_) {
        header["levels"].push_back({{"radius", l.radius},
                                    {"exponent", l.exponent},
                                    {"patch_size", l.patch_size},
                                    {"width", l.width},
                                    {"height", l.height}});
        for (const std::vector<float>* v : {&l.bandwidth, &l.maximum})
            payload.append(reinterpret_cast<const char*>(v->data()), v->size() * sizeof(float));
    }
    header["checksum"] = std::to_string(fnv1a_words(payload.data(), payload.size()));
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    write_text_atomically(path, std::string(kMagic) + "\n" + header.dump() + "\n" + payload);
}

EnvBandwidthHierarchy EnvBandwidthHierarchy::load(const std::filesystem::path& path) {
    const std::string file = path.string(), text = read_text_file(path);
    const size_t l1 = text.find('\n'), l2 = l1 == std::string::npos ? l1 : text.find('\n', l1 + 1);
    if (l2 == std::string::npos || text.compare(0, l1, kMagic) != 0)
        throw Error(file, "header", "not a freqlab bandwidth-hierarchy file");
    const nlohmann::json hd =
        nlohmann::json::parse(text.substr(l1 + 1, l2 - l1 - 1), nullptr, false);
    if (hd.is_discarded() || hd.value("version", -1) != kFormatVersion || !hd.contains("levels"))
        throw Error(file, "version", "expected version " + std::to_string(kFormatVersion));
    const char* data = text.data() + l2 + 1;
    const size_t size = text.size() - l2 - 1;
    if (hd.value("checksum", std::string()) != std::to_string(fnv1a_words(data, size)))
        throw Error(file, "checksum", "the payload does not match its checksum (damaged file)");
    EnvBandwidthHierarchy h;
    h.env_width_ = hd.value("env_width", 0);
    h.rotation_deg_ = hd.value("rotation_deg", 0.0f);
    h.nyquist_ = hd.value("nyquist", 0.0);
    h.content_hash_ = std::stoull(hd.value("content_hash", std::string("0")));
    size_t offset = 0;
    for (const auto& jl : hd["levels"]) {
        Level l;
        l.radius = jl.value("radius", 0.0);
        l.exponent = jl.value("exponent", 1.0);
        l.patch_size = jl.value("patch_size", 16);
        l.width = jl.value("width", 0);
        l.height = jl.value("height", 0);
        const size_t n = size_t(l.width) * size_t(l.height);
        if (offset + 2 * n * sizeof(float) > size)
            throw Error(file, "payload", "shorter than its levels (truncated?)");
        for (std::vector<float>* v : {&l.bandwidth, &l.maximum}) {
            v->resize(n);
            std::memcpy(v->data(), data + offset, n * sizeof(float));
            offset += n * sizeof(float);
        }
        h.levels_.push_back(std::move(l));
    }
    if (offset != size) throw Error(file, "payload", "longer than its levels");
    return h;
}

LayerSet bandwidth_layers(const EnvironmentMap& env, const EnvBandwidthHierarchy& h, int width) {
    const int height = std::max(width / 2, 1);
    LayerSet layers(width, height);
    Layer& color = layers.add("color", LayerKind::Color, 3, "the environment map (lat-long)");
    std::vector<vec3> directions(size_t(width) * height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const vec3 d = env.uv_to_direction(vec2((x + 0.5f) / width, (y + 0.5f) / height));
            directions[size_t(y) * width + size_t(x)] = d;
            const vec3 c = env.eval(d);
            for (int k = 0; k < 3; ++k)
                color.data[3 * (size_t(y) * width + size_t(x)) + size_t(k)] = c[k];
        }
    for (size_t l = 0; l < h.levels().size(); ++l) {
        char name[48], description[160];
        const double deg = h.levels()[l].radius * 180.0 / kPiD;
        std::snprintf(name, sizeof name, "B_L r=%.3gdeg", deg);
        std::snprintf(description, sizeof description,
                      "environment bandwidth, cycles/rad, in a cos^%.3g window of radius %.3g deg "
                      "(Nyquist %.3g)",
                      h.levels()[l].exponent, deg, h.nyquist());
        Layer& layer = layers.add(name, LayerKind::Continuous, 1, description);
        for (size_t i = 0; i < directions.size(); ++i)
            layer.data[i] = float(h.level_value(int(l), directions[i]));
    }
    return layers;
}

EnvBandwidthHierarchy EnvBandwidthHierarchy::cached(const EnvironmentMap& env,
                                                    std::string* path_used) {
    const RgbImage& image = env.image();
    uint64_t key = fnv1a_words(reinterpret_cast<const char*>(image.pixels.data()),
                               image.pixels.size() * sizeof(vec3));
    key = fnv1a(std::to_string(image.width) + "x" + std::to_string(image.height) + "@" +
                    std::to_string(env.rotation_deg()) + "*" + std::to_string(env.scale()) + "v" +
                    std::to_string(kFormatVersion),
                key);
    char name[64];
    std::snprintf(name, sizeof name, "envbw_%016llx.bin", static_cast<unsigned long long>(key));
    const std::filesystem::path path = cache_directory() / "envbw" / name;
    if (path_used) *path_used = path.string();
    std::error_code ec;
    if (std::filesystem::is_regular_file(path, ec)) {
        try {
            EnvBandwidthHierarchy h = load(path);
            if (h.content_hash_ == key) return h;
        } catch (const Error&) {
            // stale or damaged: rebuilt below
        }
    }
    EnvBandwidthHierarchy h = build(env);
    h.content_hash_ = key;
    try {
        h.save(path);
    } catch (const std::exception&) {
    }
    return h;
}

}  // namespace freqlab
