// The check macros: MPM_VERIFY always throws the requested error with the expression, file and
// line; MPM_ASSERT throws std::logic_error in debug builds and vanishes with NDEBUG.
#include <mpm/core/error.h>

#include <doctest/doctest.h>

#include <stdexcept>
#include <string>

TEST_CASE("MPM_VERIFY names the message, the expression, the file and the line") {
  const int particles = 0;
  const int line = __LINE__ + 2;
  try {
    MPM_VERIFY(particles > 0, mpm::InputError, "a scene needs particles");
    FAIL("MPM_VERIFY did not throw");
  } catch (const mpm::InputError& e) {
    const std::string what = e.what();
    CHECK(what.find("a scene needs particles") == 0);
    CHECK(what.find("'particles > 0'") != std::string::npos);
    CHECK(what.find("test_error.cpp:" + std::to_string(line)) != std::string::npos);
  }
  CHECK_NOTHROW(MPM_VERIFY(particles == 0, mpm::InputError, "unused"));
}

TEST_CASE("MPM_ASSERT is a debug-only check") {
  int evaluated = 0;
  [[maybe_unused]] auto count = [&] { return ++evaluated > 100; };
#ifdef NDEBUG
  CHECK_NOTHROW(MPM_ASSERT(count()));
  CHECK(evaluated == 0);  // not even evaluated in release builds
#else
  CHECK_THROWS_AS(MPM_ASSERT(count()), std::logic_error);
  CHECK(evaluated == 1);
#endif
}
