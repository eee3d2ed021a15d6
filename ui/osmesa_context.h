// Plain-function wrapper around OSMesa (see osmesa_context.cpp for why it is separate).
#pragma once

namespace freqlab::ui {

struct OsMesaContextHandle;
using GlProc = void (*)();

OsMesaContextHandle* osmesa_create(int width, int height);  // made current; null on failure
void osmesa_destroy(OsMesaContextHandle* handle);
GlProc osmesa_proc_address(const char* name);

}  // namespace freqlab::ui
