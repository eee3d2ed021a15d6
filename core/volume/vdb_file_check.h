// A walk over an OpenVDB file's length-prefixed fields before OpenVDB reads it (issue
// "Reliability": fuzz_vdb). OpenVDB allocates (and fills) every string and metadata value at
// the size the file declares before reading it, so a damaged 10 kB file cost 2 GB and 3 s
// before failing. This walk follows the layout of OpenVDB's io::Archive (header, file
// metadata, then per grid its descriptor, compression flags, metadata and transform type),
// checks each declared size against the bytes the file has left, and skips a grid's binary
// body by the end offset its descriptor gives. Where the layout is not one it knows (an
// older file version, a stream written without offsets) it stops and lets OpenVDB decide:
// it only refuses what no reader could make sense of.
#pragma once

#include <string>

namespace freqlab {

// Empty when the walk found nothing impossible; else what is wrong and where (byte offset).
std::string check_vdb_layout(const std::string& path);

}  // namespace freqlab
