// Writing outputs so that nothing half-written is ever left behind: every file is written to
// a temporary sibling and renamed into place only when complete.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace freqlab {

// Calls write(tmp_path) and renames tmp_path onto `path`; removes tmp_path on any exception.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path&)>& write);
void write_text_atomically(const std::filesystem::path& path, const std::string& text);
std::string read_text_file(const std::filesystem::path& path);  // throws Error naming the file
// A failed write's reason for an Error: `reason` (else errno's text), prefixed by "no space left
// on the device (N bytes available in DIR)" when the file's folder has under 1 MB free.
std::string describe_write_failure(const std::filesystem::path& path, std::string reason);

// freqlab's cache folder: $FREQLAB_CACHE_DIR, else $XDG_CACHE_HOME/freqlab, else
// ~/.cache/freqlab, else a temporary folder.
std::filesystem::path cache_directory();

}  // namespace freqlab
