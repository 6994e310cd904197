// MS_CHECK(cond) << "message": aborts on a broken invariant (a programming error, not bad input).
#pragma once

#include <sstream>

namespace ms::internal {

class CheckFailure {
 public:
  CheckFailure(const char* file, int line, const char* condition);
  [[noreturn]] ~CheckFailure();
  std::ostream& stream() { return stream_; }

 private:
  std::ostringstream stream_;
};

}  // namespace ms::internal

#define MS_CHECK(condition) \
  if (condition) {          \
  } else                    \
    ::ms::internal::CheckFailure(__FILE__, __LINE__, #condition).stream()
