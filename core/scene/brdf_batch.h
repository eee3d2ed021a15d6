// One BRDF at one shading point, evaluated and sampled for many directions at once: the loops
// run over arrays (structure of arrays) of straight-line float code, which the compiler turns
// into SIMD code. This is what the direct-lighting integrator (render/direct_lighting.cpp)
// calls for its environment and BRDF samples; scene/brdf.cpp stays the one-direction
// reference that the sampling tests (chi-square, pdf quadrature) check, and
// tests/test_brdf_batch.cpp holds the two to the same values.
//
// Same models and formulas as scene/brdf.h, with math/fast_math.h in place of libm. Every
// model is the albedo times a scalar lobe, so `value` is that scalar: f = albedo x value.
#pragma once

#include "scene/brdf.h"

namespace freqlab {

class BrdfBatch {
  public:
    BrdfBatch(const Brdf& brdf, const vec3& wo_world);

    // For n world directions (x, y, z): value = f / albedo and the BRDF strategy's pdf.
    void eval(int n, const float* x, const float* y, const float* z, float* value,
              float* pdf) const;
    // n samples from the uniforms (u1[i], u2[i]): world directions, value and pdf as eval()
    // (pdf 0: no sample). Mirrors are not sampled here (pdf 0): they are followed, not shaded.
    void sample(int n, const float* u1, const float* u2, float* x, float* y, float* z, float* value,
                float* pdf) const;

    // The lobe's parameters at the point, in the shading frame (z along the normal).
    struct Lobe {
        BrdfType type;
        vec3 wo;              // local, unit
        float exponent;       // Phong
        float alpha, alpha2;  // Beckmann / GGX
        float g1_wo = 0;      // Smith G1 of wo (microfacet models)
        Frame phong_frame;    // about the mirror direction of wo (Phong sampling)
        bool valid;           // wo above the surface; else everything is 0
    };

  private:
    Frame frame_;
    Lobe lobe_;
};

}  // namespace freqlab
