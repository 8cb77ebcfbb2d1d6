#!/usr/bin/env bash
# Every Catch2 test case declared under tests/ is compiled into engage_tests and listed by it
# (so that catch_discover_tests gives it a ctest entry, which -w NoTests makes fail if it
# matches nothing). A file left out of tests/CMakeLists.txt, or a case hidden by a tag, fails.
#   bash tests/CountCases.sh ENGAGE_TESTS SOURCE_DIR
set -euo pipefail
tests=$1
source=$2
declared=$(cd "$source/tests" && grep -rhE '^TEST_CASE\(' --include='*.cpp' \
  --exclude-dir=bench --exclude-dir=fuzz . | wc -l)
# (Catch2 v2 exits with the number of cases it lists.)
listed=$({ "$tests" --list-test-names-only || true; } | grep -c .)
echo "Catch2 test cases: $declared declared under tests/, $listed in engage_tests"
if [ "$declared" -ne "$listed" ]; then
  echo "declared and listed differ: a test file is not built, or a case is hidden" >&2
  exit 1
fi
