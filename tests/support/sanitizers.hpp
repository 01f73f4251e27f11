// Whether this test binary runs under AddressSanitizer (setup.sh's sanitizer build). A test that
// runs a long simulation to check its physics skips itself there: the sanitizers slow the sweep
// about sevenfold, and shorter tests run the same code.
#pragma once

namespace sandflow::test {

#if defined(__SANITIZE_ADDRESS__)  // GCC
inline constexpr bool kSanitizers = true;
#elif defined(__has_feature)  // clang
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitizers = true;
#else
inline constexpr bool kSanitizers = false;
#endif
#else
inline constexpr bool kSanitizers = false;
#endif

}  // namespace sandflow::test
