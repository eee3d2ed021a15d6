// libFuzzer target (issue "Reliability"): the workbench's session file
// (session/session_file.h): every view field, every render setting, the bake part. Bad input
// must end in freqlab::Error naming the file and field.
#include <string>

#include "base/error.h"
#include "fuzz_support.h"
#include "session/session_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        (void)freqlab::read_session_file(std::string(reinterpret_cast<const char*>(data), size),
                                         "fuzz-session.json");
    } catch (const freqlab::Error& e) {
        fuzz_report(e);
    }
    return 0;
}
