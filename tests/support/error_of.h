#pragma once
#include <gtest/gtest.h>

#include <exception>
#include <string>

#include "rubble/error.h"

namespace rubble::test {

/// The message of the rubble::Error that `f` throws; a test failure (and "") if it throws nothing or another type.
template <class F>
std::string errorOf(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "threw a non-rubble exception: " << e.what();
        return {};
    }
    ADD_FAILURE() << "expected a rubble::Error, but the call was accepted";
    return {};
}

}  // namespace rubble::test
