#pragma once
// Reading a whole input file (scene files, OBJ meshes) without trusting it: only a regular file is read (a FIFO
// would block for ever, a device such as /dev/zero never ends), and only up to a size stated in
// include/rubble/limits.h, checked before a byte is read and again while reading (the file may grow).
#include <cstdint>
#include <string>

namespace rubble::detail {

/// The file's contents. Throws rubble::Error naming the path and the problem: missing or unreadable, not a regular
/// file, or larger than `maxBytes` (`what` names the kind of file in the message: "a scene file", "an OBJ file").
std::string readRegularFile(const std::string& path, std::uint64_t maxBytes, const char* what);

}  // namespace rubble::detail
