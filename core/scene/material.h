// Materials of the scene model: the reflectance models method A and the reference shade with
// (Lambert, Phong, Beckmann / GGX microfacet, perfect mirror) and their albedo textures.
// Evaluation and sampling of the BRDFs joins this folder with the reference integrator, so
// that method A (render/) and method B (volume/) share one copy.
#pragma once

#include <memory>
#include <string>

#include "base/enum_names.h"
#include "image/image_io.h"
#include "math/types.h"

namespace freqlab {

enum class BrdfType { Lambert, Phong, Beckmann, Ggx, Mirror };
inline constexpr EnumName<BrdfType> kBrdfTypeNames[] = {{BrdfType::Lambert, "lambert"},
                                                        {BrdfType::Phong, "phong"},
                                                        {BrdfType::Beckmann, "beckmann"},
                                                        {BrdfType::Ggx, "ggx"},
                                                        {BrdfType::Mirror, "mirror"}};
inline const char* to_string(BrdfType type) {
    return enum_name(kBrdfTypeNames, type);
}

struct Texture {
    enum class Kind { Constant, Checker, Image } kind = Kind::Constant;
    vec3 color{0.5f};    // Constant; Checker's first colour
    vec3 color_b{0.1f};  // Checker's second colour
    float scale = 1.0f;  // Checker: squares per uv unit; Image: uv repeat
    std::shared_ptr<const RgbImage> image;
    std::string source;  // image path, for provenance

    vec3 eval(vec2 uv) const;  // bilinear, repeating
};

struct Material {
    std::string name;
    BrdfType type = BrdfType::Lambert;
    Texture albedo;
    float phong_exponent = 1.0f;  // Phong
    float roughness = 0.5f;       // Beckmann / GGX alpha, in (0, 1]
};

}  // namespace freqlab
