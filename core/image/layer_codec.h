// A LayerSet as one byte string and back: how a frame travels between processes (an MPI rank
// to rank 0, app/cluster.h) before the one writer turns it into EXR / PNG. Every field of every
// layer round-trips exactly (names, kinds, legends, palettes, the float bits), so the file rank 0
// writes is the file the rendering process would have written.
#pragma once

#include <string>
#include <vector>

#include "base/byte_stream.h"
#include "image/layers.h"

namespace freqlab {

std::string encode_layers(const LayerSet& layers);
// The same bytes into any sink (a file as they are written, a counter for their size).
void encode_layers(const LayerSet& layers, ByteSink& out);
// Throws Error naming `source` when the bytes are not a whole encoded LayerSet.
LayerSet decode_layers(std::string_view bytes, const std::string& source);
// Only the layers named in `only` (every layer's header is still checked); the names of the
// others, in their order, go to `left_out`. A frame's on-screen layer is ~5 % of its bytes.
LayerSet decode_layers(std::string_view bytes, const std::string& source,
                       const std::vector<std::string>& only, std::vector<std::string>& left_out);

}  // namespace freqlab
