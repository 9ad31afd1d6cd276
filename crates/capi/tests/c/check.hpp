// The checks the C++ test programs share: a failed `check` is counted (the program reports
// them at its end), a failed `ok` ends the program with tissue's last error message.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

#include "tissue.h"

inline int failures = 0;

inline void check(bool ok, const std::string& what) {
    if (!ok) {
        std::fprintf(stderr, "FAILED: %s\n", what.c_str());
        ++failures;
    }
}

/// tissue's last error message on this thread (its size asked first).
inline std::string last_error() {
    std::string text(tissue_last_error(nullptr, 0), '\0');
    if (!text.empty()) {
        tissue_last_error(text.data(), text.size());
        text.pop_back();
    }
    return text;
}

inline void ok(tissue_status s, const char* what) {
    if (s != TISSUE_OK) {
        std::fprintf(stderr, "FAILED: %s gave %d: %s\n", what, static_cast<int>(s),
                     last_error().c_str());
        std::exit(1);
    }
}
