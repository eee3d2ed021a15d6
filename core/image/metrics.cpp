#include "image/metrics.h"

#include <cmath>

#include "base/error.h"
#include "math/types.h"

namespace freqlab {

namespace {

// Separable 11-tap Gaussian (sigma 1.5, Wang et al. 2004) in double. Not OIIO's convolve:
// it filters in float, and SSIM subtracts nearly equal moments (E[a^2] - E[a]^2), which
// float leaves with errors of order 1e-5 in the result (see test_metrics.cpp). Only the
// valid region (no border handling) is used, so only that is computed.
constexpr int kRadius = 5;

std::vector<double> gaussian_taps() {
    std::vector<double> k(2 * kRadius + 1);
    double sum = 0;
    for (int i = -kRadius; i <= kRadius; ++i)
        sum += k[i + kRadius] = std::exp(-i * i / (2 * 1.5 * 1.5));
    for (double& v : k) v /= sum;
    return k;
}

std::vector<double> blur_valid(const std::vector<double>& v, int w, int h) {
    static const std::vector<double> k = gaussian_taps();
    std::vector<double> rows(v.size(), 0.0), out(v.size(), 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = kRadius; x < w - kRadius; ++x) {
            double s = 0;
            for (int i = -kRadius; i <= kRadius; ++i)
                s += k[i + kRadius] * v[size_t(y) * w + x + i];
            rows[size_t(y) * w + x] = s;
        }
    for (int y = kRadius; y < h - kRadius; ++y)
        for (int x = kRadius; x < w - kRadius; ++x) {
            double s = 0;
            for (int i = -kRadius; i <= kRadius; ++i)
                s += k[i + kRadius] * rows[size_t(y + i) * w + x];
            out[size_t(y) * w + x] = s;
        }
    return out;
}

}  // namespace

double ssim(const std::vector<float>& a, const std::vector<float>& b, int w, int h) {
    const int r = kRadius;
    if (w <= 2 * r || h <= 2 * r) {
        // Too small for one full window: fall back to a single global window.
        double ma = 0, mb = 0;
        for (size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
        ma /= a.size(), mb /= b.size();
        double va = 0, vb = 0, cov = 0;
        for (size_t i = 0; i < a.size(); ++i)
            va += (a[i] - ma) * (a[i] - ma), vb += (b[i] - mb) * (b[i] - mb),
                cov += (a[i] - ma) * (b[i] - mb);
        va /= a.size(), vb /= a.size(), cov /= a.size();
        const double c1 = 1e-4, c2 = 9e-4;
        return ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
    }
    std::vector<double> da(a.begin(), a.end()), db(b.begin(), b.end());
    std::vector<double> aa(a.size()), bb(a.size()), ab(a.size());
    for (size_t i = 0; i < a.size(); ++i)
        aa[i] = da[i] * da[i], bb[i] = db[i] * db[i], ab[i] = da[i] * db[i];
    auto blur = [&](const std::vector<double>& v) { return blur_valid(v, w, h); };
    const std::vector<double> mu_a = blur(da), mu_b = blur(db), s_aa = blur(aa), s_bb = blur(bb),
                              s_ab = blur(ab);
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
    double sum = 0;
    long n = 0;
    for (int y = r; y < h - r; ++y)
        for (int x = r; x < w - r; ++x) {
            const size_t i = size_t(y) * w + x;
            const double ma = mu_a[i], mb = mu_b[i];
            const double va = s_aa[i] - ma * ma, vb = s_bb[i] - mb * mb, cov = s_ab[i] - ma * mb;
            sum +=
                ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
            ++n;
        }
    return sum / n;
}

ImageMetrics compare_layers(const LayerSet& test, const LayerSet& ref, const std::string& name,
                            double eps) {
    if (test.width() != ref.width() || test.height() != ref.height())
        throw Error("", "size",
                    "images differ in size: test is " + std::to_string(test.width()) + "x" +
                        std::to_string(test.height()) + ", reference is " +
                        std::to_string(ref.width()) + "x" + std::to_string(ref.height()));
    const Layer& t = test.get(name);
    const Layer& r = ref.get(name);
    if (t.channels != r.channels)
        throw Error("", "layer " + name,
                    "channel counts differ: " + std::to_string(t.channels) + " vs " +
                        std::to_string(r.channels));
    ImageMetrics m;
    double sq = 0, rel = 0;
    long counted = 0;
    const int nch = std::min(t.channels, 3);
    const size_t npix = test.pixel_count();
    std::vector<float> lt(npix), lr(npix);
    for (size_t p = 0; p < npix; ++p) {
        vec3 ct(0.0f), cr(0.0f);
        for (int c = 0; c < nch; ++c) {
            const float tv = t.data[p * t.channels + c], rv = r.data[p * r.channels + c];
            if (!std::isfinite(rv))
                throw Error("",
                            "reference pixel (" + std::to_string(p % test.width()) + ", " +
                                std::to_string(p / test.width()) + ")",
                            "non-finite value in the reference");
            cr[c] = rv;
            if (!std::isfinite(tv)) {
                ++m.nonfinite;
                continue;
            }
            ct[c] = tv;
            const double d = double(tv) - rv;
            sq += d * d;
            rel += d * d / ((rv + eps) * (rv + eps));
            m.max_abs = std::max(m.max_abs, std::fabs(d));
            ++counted;
        }
        lt[p] = nch == 3 ? luminance(ct) : ct[0];
        lr[p] = nch == 3 ? luminance(cr) : cr[0];
    }
    m.rmse = counted ? std::sqrt(sq / counted) : 0.0;
    m.relmse = counted ? rel / counted : 0.0;
    m.ssim = ssim(lt, lr, test.width(), test.height());
    return m;
}

}  // namespace freqlab
