#version 330 core
// Maps one float layer to display colours by its kind (core/image/colormap.h is the CPU
// twin and the tests' reference): colour = exposure + sRGB, continuous = viridis LUT,
// signed = diverging LUT symmetric about 0, categorical = palette, vectors = per component.
// NaN / Inf show magenta so they never pass unnoticed; a sparse layer's no-data pixels (0) are
// transparent.
in vec2 v_uv;
out vec4 frag;
uniform sampler2D u_layer;    // R32F or RGB32F, row 0 = top row of the layer
uniform sampler2D u_lut;      // 256 x 1 (continuous / signed) or 10 x 1 (categorical)
uniform int u_mode;           // 0 colour, 1 continuous, 2 signed, 3 categorical, 4 vector
uniform float u_lo;
uniform float u_hi;
uniform float u_exposure;     // multiplier 2^EV
uniform int u_channels;
uniform int u_sparse;         // values only where a sample is: 0 elsewhere is "no data"

float to_srgb(float c) {
    c = clamp(c, 0.0, 1.0);
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

vec3 lut(float t) {
    t = clamp(t, 0.0, 1.0);
    return texture(u_lut, vec2((t * 255.0 + 0.5) / 256.0, 0.5)).rgb;
}

void main() {
    ivec2 size = textureSize(u_layer, 0);
    ivec2 texel = min(ivec2(v_uv * vec2(size)), size - 1);
    vec4 v = texelFetch(u_layer, texel, 0);
    bool bad = false;
    for (int c = 0; c < u_channels; ++c) bad = bad || isnan(v[c]) || isinf(v[c]);
    if (bad) { frag = vec4(1.0, 0.0, 1.0, 1.0); return; }
    // No data is transparent: over colour it shows the colour, not the colormap's 0.
    if (u_sparse == 1 && all(equal(v.rgb * vec3(1.0, float(u_channels > 1), float(u_channels > 2)),
                                   vec3(0.0)))) {
        frag = vec4(0.0);
        return;
    }
    vec3 rgb;
    if (u_mode == 0) {
        vec3 c = u_channels >= 3 ? v.rgb : vec3(v.r);
        rgb = vec3(to_srgb(u_exposure * c.r), to_srgb(u_exposure * c.g), to_srgb(u_exposure * c.b));
    } else if (u_mode == 1) {
        rgb = lut((v.r - u_lo) / (u_hi - u_lo));
    } else if (u_mode == 2) {
        rgb = lut(0.5 * (v.r / u_hi + 1.0));
    } else if (u_mode == 3) {
        int n = textureSize(u_lut, 0).x;
        int i = int(round(v.r));
        i = ((i % n) + n) % n;
        rgb = texelFetch(u_lut, ivec2(i, 0), 0).rgb;
    } else {
        rgb = clamp((v.rgb - vec3(u_lo)) / (u_hi - u_lo), 0.0, 1.0);
    }
    frag = vec4(rgb, 1.0);
}
