#include "core/file_reading.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "rubble/error.h"

namespace rubble::detail {

std::string readRegularFile(const std::string& path, std::uint64_t maxBytes, const char* what) {
    const auto tooLarge = [&] {
        return Error(path + ": larger than " + std::to_string(maxBytes >> 20) + " MiB, the most " + what +
                     " may be (docs/limits.md)");
    };
    struct stat info {};
    if (stat(path.c_str(), &info) != 0) throw Error("cannot open " + path + ": " + std::strerror(errno));
    if (S_ISDIR(info.st_mode)) throw Error(path + ": is a directory, not " + what);
    if (!S_ISREG(info.st_mode)) throw Error(path + ": is not a regular file (a device, FIFO or socket), not " + what);
    if (static_cast<std::uint64_t>(info.st_size) > maxBytes) throw tooLarge();
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
    if (!file) throw Error("cannot open " + path + ": " + std::strerror(errno));
    std::string text;
    text.reserve(static_cast<std::size_t>(info.st_size));
    char buffer[1 << 16];
    for (;;) {
        const std::size_t got = std::fread(buffer, 1, sizeof buffer, file.get());
        text.append(buffer, got);
        if (text.size() > maxBytes) throw tooLarge();
        if (got < sizeof buffer) break;
    }
    if (std::ferror(file.get())) throw Error("cannot read " + path + ": " + std::strerror(errno));
    return text;
}

}  // namespace rubble::detail
