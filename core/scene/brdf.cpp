#include "scene/brdf.h"

#include <cmath>

namespace freqlab {

float Brdf::beckmann_d(float cos_h, float alpha) {
    if (cos_h <= 0) return 0.0f;
    const float c2 = cos_h * cos_h, tan2 = (1.0f - c2) / c2, a2 = alpha * alpha;
    return std::exp(-tan2 / a2) / (kPi * a2 * c2 * c2);
}

float Brdf::ggx_d(float cos_h, float alpha) {
    if (cos_h <= 0) return 0.0f;
    const float c2 = cos_h * cos_h, tan2 = (1.0f - c2) / c2, a2 = alpha * alpha;
    const float k = a2 + tan2;
    return a2 / (kPi * c2 * c2 * k * k);
}

float Brdf::beckmann_g1(float cos_v, float alpha) {
    if (cos_v <= 0) return 0.0f;
    const float tan_v = std::sqrt(std::max(0.0f, 1.0f - cos_v * cos_v)) / cos_v;
    if (tan_v == 0.0f) return 1.0f;
    const float a = 1.0f / (alpha * tan_v);
    return a >= 1.6f ? 1.0f : (3.535f * a + 2.181f * a * a) / (1.0f + 2.276f * a + 2.577f * a * a);
}

float Brdf::ggx_g1(float cos_v, float alpha) {
    if (cos_v <= 0) return 0.0f;
    const float tan2 = (1.0f - cos_v * cos_v) / (cos_v * cos_v);
    return 2.0f / (1.0f + std::sqrt(1.0f + alpha * alpha * tan2));
}

float Brdf::microfacet_d(float cos_h) const {
    return type_ == BrdfType::Ggx ? ggx_d(cos_h, alpha_) : beckmann_d(cos_h, alpha_);
}

float Brdf::microfacet_g1(float cos_v) const {
    return type_ == BrdfType::Ggx ? ggx_g1(cos_v, alpha_) : beckmann_g1(cos_v, alpha_);
}

vec3 Brdf::eval(const vec3& wo_w, const vec3& wi_w) const {
    const vec3 wo = frame_.to_local(wo_w), wi = frame_.to_local(wi_w);
    if (wo.z <= 0 || wi.z <= 0) return vec3(0.0f);
    switch (type_) {
        case BrdfType::Lambert:
            return albedo_ * kInvPi;
        case BrdfType::Phong: {
            const vec3 r(-wo.x, -wo.y, wo.z);
            const float c = glm::dot(r, wi);
            return c > 0 ? albedo_ * ((exponent_ + 2.0f) / kTwoPi * std::pow(c, exponent_))
                         : vec3(0.0f);
        }
        case BrdfType::Beckmann:
        case BrdfType::Ggx: {
            const vec3 h = glm::normalize(wo + wi);
            const float value = microfacet_d(h.z) * microfacet_g1(wo.z) * microfacet_g1(wi.z) /
                                (4.0f * wo.z * wi.z);
            return albedo_ * value;
        }
        case BrdfType::Mirror:
            return vec3(0.0f);  // a delta: never hit by a sampled direction
    }
    return vec3(0.0f);
}

float Brdf::pdf(const vec3& wo_w, const vec3& wi_w) const {
    const vec3 wo = frame_.to_local(wo_w), wi = frame_.to_local(wi_w);
    if (wo.z <= 0) return 0.0f;
    switch (type_) {
        case BrdfType::Lambert:
            return cosine_hemisphere_pdf(wi.z);
        case BrdfType::Phong:
            return power_cosine_pdf(exponent_, glm::dot(vec3(-wo.x, -wo.y, wo.z), wi));
        case BrdfType::Beckmann:
        case BrdfType::Ggx: {
            const vec3 sum = wo + wi;
            const float len = glm::length(sum);
            if (len < 1e-7f) return 0.0f;
            const vec3 h = sum / len;
            const float wo_h = glm::dot(wo, h);
            if (wo_h <= 0) return 0.0f;
            return microfacet_d(h.z) * h.z / (4.0f * wo_h);
        }
        case BrdfType::Mirror:
            return 0.0f;
    }
    return 0.0f;
}

BrdfSample Brdf::sample(const vec3& wo_w, float u1, float u2) const {
    BrdfSample s;
    const vec3 wo = frame_.to_local(wo_w);
    if (wo.z <= 0) return s;
    vec3 wi;
    switch (type_) {
        case BrdfType::Lambert:
            wi = sample_cosine_hemisphere(u1, u2);
            break;
        case BrdfType::Phong: {
            const Frame lobe(vec3(-wo.x, -wo.y, wo.z));
            wi = lobe.to_world(sample_power_cosine(exponent_, u1, u2));
            break;
        }
        case BrdfType::Beckmann:
        case BrdfType::Ggx: {
            const float a2 = alpha_ * alpha_;
            const float tan2 = type_ == BrdfType::Ggx ? a2 * u1 / std::max(1.0f - u1, 1e-12f)
                                                      : -a2 * std::log(std::max(1.0f - u1, 1e-12f));
            const float cos_h = 1.0f / std::sqrt(1.0f + tan2);
            const float sin_h = std::sqrt(std::max(0.0f, 1.0f - cos_h * cos_h)), phi = kTwoPi * u2;
            const vec3 h(sin_h * std::cos(phi), sin_h * std::sin(phi), cos_h);
            wi = reflect_about(wo, h);
            break;
        }
        case BrdfType::Mirror: {
            s.wi = frame_.to_world(vec3(-wo.x, -wo.y, wo.z));
            s.pdf = 1.0f;  // by convention for deltas; f carries the albedo
            s.f = albedo_;
            return s;
        }
    }
    s.wi = frame_.to_world(wi);
    s.pdf = pdf(wo_w, s.wi);
    s.f = eval(wo_w, s.wi);
    return s;
}

}  // namespace freqlab
