#pragma once
#include <stdexcept>
#include <string>

namespace rubble {

/// Thrown when the API or a scene file is given input it refuses. The message names what is wrong and where.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace rubble
