// libFuzzer target (issue "Reliability"): the impulse-table file (volume/impulse_tables.h):
// magic line, JSON header, every header field, payload size and checksum. The payload past a
// matching checksum is freqlab's own (2 MB, beyond a fuzzer's input size); its finiteness is
// checked on load and by test_impulse_tables. Bad input must end in freqlab::Error.
#include "base/error.h"
#include "fuzz_support.h"
#include "volume/impulse_tables.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = write_fuzz_input(data, size, ".bin");
    try {
        (void)freqlab::ImpulseTables::load(path);
    } catch (const freqlab::Error& e) {
        fuzz_report(e);
    }
    return 0;
}
