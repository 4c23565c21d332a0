// The main of the gpu tests: doctest's, but a run whose cases all passed and some of which had
// no GPU to run on exits 77, which ctest reports as skipped (SKIP_RETURN_CODE), not passed.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

int cuda_cases_skipped();

int main(int argc, char** argv) {
  doctest::Context context(argc, argv);
  const int result = context.run();
  if (context.shouldExit() || result != 0) return result;
  return cuda_cases_skipped() > 0 ? 77 : 0;
}
