// libFuzzer target (issue "Reliability"): an environment map file read as the scene loader
// reads it (image/image_io.h, finite texels required) and turned into the importance-sampled
// map every method lights with (scene/light.h). Built twice, FUZZ_ENV_EXTENSION ".exr" and
// ".hdr" (OpenImageIO picks its reader by the extension). Bad input must end in
// freqlab::Error; a map that loads must give finite radiance and pdf.
#include <cmath>

#include "base/error.h"
#include "fuzz_support.h"
#include "image/image_file_check.h"
#include "image/image_io.h"
#include "scene/light.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace freqlab;
    const std::string path = write_fuzz_input(data, size, FUZZ_ENV_EXTENSION);
    try {
        // Inputs whose header promises more than 2^18 values are left out: their first read
        // touches up to 1 GB (the limit read_rgb_image enforces, tested in test_bad_input) and
        // would bring the run to ~100 inputs a second; the header paths stay in (read with the
        // product's checks: OIIO's own open would allocate a damaged header's attribute sizes).
        // An EXR's window is read by freqlab's own header walk before OpenEXR opens it:
        // OpenEXR sizes its line buffers from the window at open (a 249-byte file declaring
        // 983041 x 8 pixels took 3.3 s under ASan, 0.8 s and 190 MB without, as any real
        // 8-megapixel image does).
        if (check_exr_attributes(path) > (1 << 18)) return 0;
        const ImageHeader header = read_image_header(path);
        if (double(header.width) * header.height * header.channels > double(1 << 18)) return 0;
        auto image = std::make_shared<RgbImage>(read_rgb_image(path, true));
        const EnvironmentMap env(path, image, 30.0f, 1.0f);
        for (int i = 0; i < 8; ++i) {
            const float a = float(i) / 8.0f;
            vec3 direction;
            float pdf = 0.0f;
            const vec3 radiance = env.sample(vec4(a, 1.0f - a, 0.5f * a, 0.3f), &direction, &pdf);
            if (std::getenv("FREQLAB_FUZZ_VERBOSE"))
                std::fprintf(stderr, "%dx%d radiance %g %g %g pdf %g\n", image->width,
                             image->height, radiance.x, radiance.y, radiance.z, pdf);
            FUZZ_REQUIRE(std::isfinite(radiance.x + radiance.y + radiance.z) &&
                         std::isfinite(pdf) && pdf >= 0.0f);
            float eval_pdf = 0.0f;
            const vec3 seen = env.eval_with_pdf(direction, &eval_pdf);
            FUZZ_REQUIRE(std::isfinite(seen.x + seen.y + seen.z) && std::isfinite(eval_pdf));
        }
    } catch (const Error& e) {
        fuzz_report(e);
    }
    return 0;
}
