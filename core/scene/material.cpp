#include "scene/material.h"

#include <cmath>

namespace freqlab {

vec3 Texture::eval(vec2 uv) const {
    switch (kind) {
        case Kind::Constant:
            return color;
        case Kind::Checker: {
            const int parity = int(std::floor(uv.x * scale) + std::floor(uv.y * scale)) & 1;
            return parity ? color_b : color;
        }
        case Kind::Image: {
            const float x = (uv.x * scale - std::floor(uv.x * scale)) * image->width - 0.5f;
            const float y =
                (1.0f - (uv.y * scale - std::floor(uv.y * scale))) * image->height - 0.5f;
            const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
            const float fx = x - x0, fy = y - y0;
            auto texel = [&](int xi, int yi) {
                xi = ((xi % image->width) + image->width) % image->width;
                yi = ((yi % image->height) + image->height) % image->height;
                return image->at(xi, yi);
            };
            return glm::mix(glm::mix(texel(x0, y0), texel(x0 + 1, y0), fx),
                            glm::mix(texel(x0, y0 + 1), texel(x0 + 1, y0 + 1), fx), fy);
        }
    }
    return color;
}

}  // namespace freqlab
