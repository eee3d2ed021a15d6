// BRDF evaluation, sampling and pdfs for the materials of the scene model. One copy, shared
// by the reference / MIS integrator (render/), method A's radiance points and method B's baker.
//
// | model    | f(wo, wi)                                                      | sampling |
// |----------|----------------------------------------------------------------|---------------------|
// | lambert  | rho / pi                                                       | cosine hemisphere |
// | phong    | rho (e + 2) / (2 pi) max(0, r.wi)^e, r = mirror of wo (modified| cos^e lobe about r
// | |          | Phong, Lafortune & Willems: reflects at most rho)              | | | beckmann |
// rho D G / (4 |n.wi| |n.wo|), Smith G1 (Walter et al. rational) | D(h) |n.h| → reflect | | ggx |
// same with the GGX D and its exact Smith G1                      | D(h) |n.h| → reflect | | mirror
// | delta: rho along the mirror direction                          | deterministic       | No
// Fresnel term: the albedo scales the lobe, so albedo 1 is a white furnace (tested).
#pragma once

#include "math/sampling.h"
#include "scene/material.h"

namespace freqlab {

struct BrdfSample {
    vec3 wi{0.0f};
    float pdf = 0.0f;  // solid-angle density; 0 when the sample failed
    vec3 f{0.0f};      // BRDF value (without the cosine)
};

class Brdf {
  public:
    // `normal` is the shading normal, `albedo` the texture value at the point.
    Brdf(const Material& material, const vec3& albedo, const vec3& normal)
        : type_(material.type),
          albedo_(albedo),
          frame_(normal),
          exponent_(material.phong_exponent),
          alpha_(material.roughness) {}

    bool is_delta() const { return type_ == BrdfType::Mirror; }
    const Frame& frame() const { return frame_; }
    const vec3& albedo() const { return albedo_; }
    BrdfType type() const { return type_; }
    float phong_exponent() const { return exponent_; }
    float roughness() const { return alpha_; }

    vec3 eval(const vec3& wo, const vec3& wi) const;  // world directions, both pointing away
    float pdf(const vec3& wo, const vec3& wi) const;
    BrdfSample sample(const vec3& wo, float u1, float u2) const;

    // Microfacet pieces, exposed for tests.
    static float beckmann_d(float cos_h, float alpha);
    static float ggx_d(float cos_h, float alpha);
    static float beckmann_g1(float cos_v, float alpha);
    static float ggx_g1(float cos_v, float alpha);

  private:
    float microfacet_d(float cos_h) const;
    float microfacet_g1(float cos_v) const;

    BrdfType type_;
    vec3 albedo_;
    Frame frame_;
    float exponent_, alpha_;
};

}  // namespace freqlab
