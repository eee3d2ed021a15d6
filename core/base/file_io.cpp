#include "base/file_io.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "base/error.h"

namespace freqlab {

namespace fs = std::filesystem;

void write_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
    // Keep the real extension last: image writers pick the format from it.
    fs::path tmp = path;
    tmp.replace_filename("." + path.stem().string() + ".tmp" + std::to_string(getpid()) +
                         path.extension().string());
    try {
        write(tmp);
        fs::rename(tmp, path);
    } catch (...) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw;
    }
}

void write_text_atomically(const fs::path& path, const std::string& text) {
    write_atomically(path, [&](const fs::path& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        out << text;
        out.close();
        if (!out)
            throw Error(path.string(), "",
                        "could not write file: " + describe_write_failure(path, ""));
    });
}

std::string describe_write_failure(const fs::path& path, std::string reason) {
    if (reason.empty()) reason = errno ? std::string(std::strerror(errno)) : "no reason given";
    std::error_code ec;
    const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    const fs::space_info space = fs::space(dir, ec);
    if (!ec && space.available < (uintmax_t(1) << 20))
        return "no space left on the device (" + std::to_string(space.available) +
               " bytes available in " + dir.string() + "): " + reason;
    return reason;
}

std::string read_text_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw Error(path.string(), "", "cannot open file (does it exist and is it readable?)");
    const std::streamoff size = in.tellg();
    std::string text(size_t(std::max<std::streamoff>(size, 0)), '\0');
    in.seekg(0);
    if (!in.read(text.data(), std::streamsize(text.size())))
        throw Error(path.string(), "", "could not read the whole file");
    return text;
}

MappedFile::MappedFile(const fs::path& path, MapPages pages) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        throw Error(path.string(), "", "cannot open file (does it exist and is it readable?)");
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        throw Error(path.string(), "", "not a regular file");
    }
    size_ = size_t(st.st_size);
    if (size_ > 0) {
        void* p = ::mmap(nullptr, size_, PROT_READ,
                         MAP_PRIVATE | (pages == MapPages::Populate ? MAP_POPULATE : 0), fd, 0);
        if (p == MAP_FAILED) {
            const std::string why = std::strerror(errno);
            ::close(fd);
            throw Error(path.string(), "", "cannot map the file: " + why);
        }
        data_ = static_cast<const char*>(p);
    }
    ::close(fd);  // the mapping stays valid
}

MappedFile::~MappedFile() {
    if (data_) ::munmap(const_cast<char*>(data_), size_);
}

// $NAME in bytes (`fallback` MB when unset); anything but a number of megabytes >= 0 is
// refused naming the variable.
size_t megabytes_from_environment(const char* name, double fallback) {
    const char* env = std::getenv(name);
    double mb = fallback;
    if (env && *env) {
        char* end = nullptr;
        mb = std::strtod(env, &end);
        if (end == env || *end != '\0' || !(mb >= 0.0) || mb > 1e9)
            throw Error(name, "", std::string("expected megabytes >= 0, got '") + env + "'");
    }
    return size_t(mb * 1024.0 * 1024.0);
}

fs::path cache_directory() {
    if (const char* d = std::getenv("FREQLAB_CACHE_DIR"); d && *d) return d;
    if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return fs::path(x) / "freqlab";
    if (const char* h = std::getenv("HOME"); h && *h) return fs::path(h) / ".cache" / "freqlab";
    return fs::temp_directory_path() / "freqlab-cache";
}

}  // namespace freqlab
