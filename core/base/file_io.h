// Writing outputs so that nothing half-written is ever left behind: every file is written to
// a temporary sibling and renamed into place only when complete.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace freqlab {

// Calls write(tmp_path) and renames tmp_path onto `path`; removes tmp_path on any exception.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path&)>& write);
void write_text_atomically(const std::filesystem::path& path, const std::string& text);
std::string read_text_file(const std::filesystem::path& path);  // throws Error naming the file
// A failed write's reason for an Error: `reason` (else errno's text), prefixed by "no space left
// on the device (N bytes available in DIR)" when the file's folder has under 1 MB free.
std::string describe_write_failure(const std::filesystem::path& path, std::string reason);

// A file's bytes, mapped read-only and populated in one call (MAP_POPULATE): a 50 MB recorded
// frame read into a fresh string cost ~250 ms of page faults on these machines, its mapping a
// few ms. Throws Error naming the file when it cannot be opened or mapped. MapPages::OnTouch:
// pages are mapped as they are touched (a read of a few parts of a large file).
enum class MapPages { Populate, OnTouch };
class MappedFile {
  public:
    explicit MappedFile(const std::filesystem::path& path, MapPages pages = MapPages::Populate);
    ~MappedFile();
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    std::string_view bytes() const { return {data_, size_}; }

  private:
    const char* data_ = nullptr;
    size_t size_ = 0;
};

// freqlab's cache folder: $FREQLAB_CACHE_DIR, else $XDG_CACHE_HOME/freqlab, else
// ~/.cache/freqlab, else a temporary folder.
std::filesystem::path cache_directory();

// $NAME in bytes (`fallback` MB when unset); anything but a number of megabytes >= 0 is
// refused naming the variable.
size_t megabytes_from_environment(const char* name, double fallback);

}  // namespace freqlab
