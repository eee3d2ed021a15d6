#include "scene/light.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "base/error.h"
#include "math/fast_atan2.h"
#include "math/fast_math.h"

namespace freqlab {

namespace {

std::string short_number(float v) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", double(v));
    return text;
}

}  // namespace

LightSample sample_light(const Light& light, const vec3& p, vec2 u) {
    LightSample s;
    switch (light.type) {
        case LightType::Point: {
            const vec3 to = light.position - p;
            s.distance = glm::length(to);
            if (!(s.distance > 0.0f)) return s;
            s.direction = to / s.distance;
            s.intensity = light.intensity;
            s.irradiance = light.intensity / (s.distance * s.distance);
            break;
        }
        case LightType::Directional:
            s.direction = -light.direction;
            s.irradiance = s.intensity = light.intensity;
            break;
        case LightType::Quad: {
            const vec3 q = light.corner + u.x * light.edge_u + u.y * light.edge_v;
            const vec3 to = q - p;
            s.distance = glm::length(to);
            if (!(s.distance > 0.0f)) return s;
            s.direction = to / s.distance;
            const vec3 cross = glm::cross(light.edge_u, light.edge_v);
            const float area = glm::length(cross);
            s.emitter_normal = cross / area;
            s.emitter_cos = -glm::dot(s.direction, s.emitter_normal);
            s.intensity = light.intensity * area;  // kept behind the quad (its lit medium)
            if (s.emitter_cos <= 0.0f) return s;
            s.irradiance = light.intensity * (area * s.emitter_cos / (s.distance * s.distance));
            break;
        }
        case LightType::Environment:
        case LightType::Sky:
            return s;  // EnvironmentMap::sample
    }
    s.valid = true;
    return s;
}

EnvironmentMap::EnvironmentMap(std::string source, std::shared_ptr<const RgbImage> image,
                               float rotation_deg, float scale, float spin_deg_per_s)
    : source_(std::move(source)),
      image_(std::move(image)),
      rotation_deg_(rotation_deg),
      scale_(scale),
      spin_deg_per_s_(spin_deg_per_s) {
    const int w = image_->width, h = image_->height;
    texels_.resize(size_t(w) * h);
    std::vector<float> weights(size_t(w) * h);
    for (int y = 0; y < h; ++y) {
        const float sin_theta = std::sin(kPi * (y + 0.5f) / h);
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            const vec3& texel = image_->pixels[i];
            // Radiance is >= 0: a negative texel (ringing of a resampled map; Blender's
            // city.exr has them) is read as 0 and counted, so that the loader can say so.
            const float lowest = std::min(texel.x, std::min(texel.y, texel.z));
            if (lowest < 0.0f) {
                ++negative_texels_;
                most_negative_ = std::min(most_negative_, lowest);
            }
            texels_[i].radiance = glm::max(texel, vec3(0.0f)) * scale_;
            const vec3& r = texels_[i].radiance;
            const float peak = std::max(r.x, std::max(r.y, r.z));
            if (!(peak <= kMaxEnvironmentRadiance))  // also NaN from a NaN scale
                throw Error(source_, "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")",
                            "radiance " + short_number(peak) + " (texel x scale " +
                                short_number(scale_) +
                                ") exceeds 1e20; larger values overflow the estimators' "
                                "single precision");
            weights[i] = luminance(texels_[i].radiance) * sin_theta;
        }
    }
    distribution_ = Distribution2D(weights, w, h);
    for (size_t i = 0; i < texels_.size(); ++i) texels_[i].pdf_uv = distribution_.texel_pdf(int(i));
}

std::shared_ptr<const EnvironmentMap> EnvironmentMap::at_time(float time) const {
    auto copy = std::make_shared<EnvironmentMap>(*this);
    copy->rotation_deg_ = rotation_deg_ + spin_deg_per_s_ * time;
    return copy;
}

namespace {

// direction_to_uv() and texel_index(), as straight-line code (the floor by comparison, not libm)
// that lookup_texels() inlines into a loop that vectorizes.
inline vec2 latlong_uv(const vec3& d, float rotation_rad) {
    // atan2 rather than acos(z): acos loses theta's precision near the poles, where the
    // solid-angle pdf divides by sin(theta).
    const float theta = fast_atan2(std::sqrt(d.x * d.x + d.y * d.y), d.z);
    float phi = fast_atan2(d.y, d.x) - rotation_rad;
    const float turns = phi / kTwoPi;
    float whole = float(int(turns));
    whole = whole > turns ? whole - 1.0f : whole;  // floor
    phi -= kTwoPi * whole;
    return vec2(phi / kTwoPi, theta / kPi);
}
inline int latlong_texel(vec2 uv, int w, int h) {
    const int x = std::min(int(uv.x * w), w - 1), y = std::min(int(uv.y * h), h - 1);
    return y * w + x;
}

}  // namespace

int EnvironmentMap::texel_index(vec2 uv) const {
    return latlong_texel(uv, image_->width, image_->height);
}

vec3 EnvironmentMap::eval(const vec3& d) const {
    return texels_[size_t(texel_index(direction_to_uv(d)))].radiance;
}

vec3 EnvironmentMap::eval_with_pdf(const vec3& d, float* pdf) const {
    vec2 uv;
    const int texel = texel_of(d, &uv);
    return eval_with_pdf_at(texel, uv, pdf);
}

int EnvironmentMap::texel_of(const vec3& d, vec2* uv) const {
    *uv = direction_to_uv(d);
    return texel_index(*uv);
}

vec3 EnvironmentMap::eval_with_pdf_at(int texel, vec2 uv, float* pdf) const {
    const Texel& t = texels_[size_t(texel)];
    *pdf = solid_angle_pdf(t.pdf_uv, uv);
    return t.radiance;
}

float EnvironmentMap::solid_angle_pdf(float pdf_uv, vec2 uv) {
    // d(u, v) = d(omega) / (2 pi^2 sin(theta)) on the lat-long map.
    const float sin_theta = std::sin(kPi * uv.y);
    return sin_theta > 0 ? pdf_uv / (2.0f * kPi * kPi * sin_theta) : 0.0f;
}

vec2 EnvironmentMap::direction_to_uv(const vec3& d) const {
    return latlong_uv(d, glm::radians(rotation_deg_));
}

vec3 EnvironmentMap::uv_to_direction(vec2 uv) const {
    const float phi = kTwoPi * uv.x + glm::radians(rotation_deg_), theta = kPi * uv.y;
    const float st = std::sin(theta);
    return vec3(st * std::cos(phi), st * std::sin(phi), std::cos(theta));
}

void EnvironmentMap::sample_directions(int n, const int* texel, const vec4* u, float* x, float* y,
                                       float* z, float* sin_theta) const {
    const int w = image_->width, h = image_->height;
    const double inv_w = 1.0 / w;
    // (u.z, u.w) place the sample in the texel's sampling tile (Distribution2D::tile()).
    const int shift = distribution_.tile_shift();
    const float inv_wf = 1.0f / float(w >> shift), inv_hf = 1.0f / float(h >> shift);
    const float rotation = glm::radians(rotation_deg_);
    for (int i = 0; i < n; ++i) {
        // Row and column in double: exact for any map, and vectorizable (an int division is not).
        const int row = int((double(texel[i]) + 0.5) * inv_w), column = texel[i] - row * w;
        const float uv_x = std::min((float(column >> shift) + u[i].z) * inv_wf, 0x1.fffffep-1f);
        const float uv_y = std::min((float(row >> shift) + u[i].w) * inv_hf, 0x1.fffffep-1f);
        float st, ct, sp, cp;
        fast_sincos(kPi * uv_y, &st, &ct);
        fast_sincos(kTwoPi * uv_x + rotation, &sp, &cp);
        x[i] = st * cp;
        y[i] = st * sp;
        z[i] = ct;
        sin_theta[i] = st;
    }
}

void EnvironmentMap::lookup_texels(int n, const float* x, const float* y, const float* z,
                                   int* texel, float* sin_theta) const {
    const int w = image_->width, h = image_->height;
    const float rotation = glm::radians(rotation_deg_);
    for (int i = 0; i < n; ++i) {
        texel[i] = latlong_texel(latlong_uv(vec3(x[i], y[i], z[i]), rotation), w, h);
        // = sin(pi v) of the lat-long map, without the sine
        sin_theta[i] = std::sqrt(x[i] * x[i] + y[i] * y[i]);
    }
    for (int i = 0; i < n; ++i) prefetch_texel(texel[i]);
}

void EnvironmentMap::texel_values(int n, const int* texel, const float* sin_theta, float* pdf,
                                  vec3* radiance) const {
    for (int i = 0; i < n; ++i) {
        const Texel& t = texels_[size_t(texel[i])];
        radiance[i] = t.radiance;
        pdf[i] = t.pdf_uv;
    }
    for (int i = 0; i < n; ++i)
        pdf[i] = sin_theta[i] > 0.0f ? pdf[i] / (2.0f * kPi * kPi * sin_theta[i]) : 0.0f;
}

vec3 EnvironmentMap::sample(const vec4& u, vec3* direction, float* pdf) const {
    return sample_at(sample_texel(u), u, direction, pdf);
}

vec3 EnvironmentMap::sample_at(int texel, const vec4& u, vec3* direction, float* pdf) const {
    // The texel already holds the density: the distribution's own pdf array is not read.
    const vec2 uv = distribution_.texel_point(texel, u);
    *direction = uv_to_direction(uv);
    return eval_with_pdf_at(texel, uv, pdf);
}

float EnvironmentMap::pdf(const vec3& d) const {
    const vec2 uv = direction_to_uv(d);
    return solid_angle_pdf(distribution_.pdf(uv), uv);
}

std::shared_ptr<const RgbImage> constant_latlong(const vec3& radiance, int width, int height) {
    auto img = std::make_shared<RgbImage>();
    img->width = width;
    img->height = height;
    img->pixels.assign(size_t(width) * height, radiance);
    return img;
}

vec3 EnvironmentMap::eval_smooth(const vec3& d) const {
    const vec2 uv = direction_to_uv(d);
    const RgbImage* image = image_.get();
    const float scale = scale_;
    const int w = image->width, h = image->height;
    const float x = uv.x * w - 0.5f, y = uv.y * h - 0.5f;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const float fx = x - x0, fy = y - y0;
    auto texel = [&](int xi, int yi) {
        xi = ((xi % w) + w) % w;
        yi = std::clamp(yi, 0, h - 1);
        return image->at(xi, yi);
    };
    return scale * glm::mix(glm::mix(texel(x0, y0), texel(x0 + 1, y0), fx),
                            glm::mix(texel(x0, y0 + 1), texel(x0 + 1, y0 + 1), fx), fy);
}

std::shared_ptr<const RgbImage> ProceduralSky::bake(int width, int height) const {
    auto img = std::make_shared<RgbImage>();
    img->width = width;
    img->height = height;
    img->pixels.resize(size_t(width) * height);
    const float texel = kPi / height;
    const float near_sun = std::cos(glm::radians(sun_angular_radius_deg) + 3.0f * texel);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            auto dir = [&](float fx, float fy) {
                const float phi = kTwoPi * fx / width, theta = kPi * fy / height;
                return vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                            std::cos(theta));
            };
            const vec3 centre = dir(x + 0.5f, y + 0.5f);
            vec3 v(0.0f);
            if (glm::dot(centre, sun_direction) > near_sun) {
                const int n = 8;  // the sun disk is a few texels wide: average its coverage
                for (int j = 0; j < n; ++j)
                    for (int i = 0; i < n; ++i)
                        v += eval(dir(x + (i + 0.5f) / n, y + (j + 0.5f) / n));
                v /= float(n * n);
            } else {
                v = eval(centre);
            }
            img->pixels[size_t(y) * width + x] = v;
        }
    return img;
}

vec3 ProceduralSky::eval(const vec3& d) const {
    const float cos_sun = glm::dot(d, sun_direction);
    if (cos_sun >= std::cos(glm::radians(sun_angular_radius_deg))) return sun_radiance;
    if (d.z < 0.0f) return ground;
    // Gradient from the horizon to the zenith, brighter around the sun (a soft aureole).
    const float t = std::pow(1.0f - d.z, 3.0f);
    const float aureole = 0.5f * std::pow(std::max(cos_sun, 0.0f), 32.0f);
    return glm::mix(zenith, horizon, t) * (1.0f + aureole);
}

}  // namespace freqlab
