// The only file that includes GL/osmesa.h: it and glad's header cannot share a translation
// unit (shared/PLATFORM.md), so context creation lives here behind plain functions.
#include <GL/osmesa.h>

#include <cstddef>
#include <vector>

#include "osmesa_context.h"

namespace freqlab::ui {

struct OsMesaContextHandle {
    OSMesaContext context = nullptr;
    std::vector<unsigned char> buffer;
};

OsMesaContextHandle* osmesa_create(int width, int height) {
    const int attribs[] = {OSMESA_FORMAT,
                           OSMESA_RGBA,
                           OSMESA_DEPTH_BITS,
                           24,
                           OSMESA_PROFILE,
                           OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION,
                           3,
                           OSMESA_CONTEXT_MINOR_VERSION,
                           3,
                           0};
    auto* h = new OsMesaContextHandle;
    h->context = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!h->context) {
        delete h;
        return nullptr;
    }
    h->buffer.resize(std::size_t(width) * height * 4);
    if (!OSMesaMakeCurrent(h->context, h->buffer.data(), GL_UNSIGNED_BYTE, width, height)) {
        OSMesaDestroyContext(h->context);
        delete h;
        return nullptr;
    }
    return h;
}

void osmesa_destroy(OsMesaContextHandle* h) {
    if (!h) return;
    OSMesaDestroyContext(h->context);
    delete h;
}

GlProc osmesa_proc_address(const char* name) {
    return reinterpret_cast<GlProc>(OSMesaGetProcAddress(name));
}

}  // namespace freqlab::ui
