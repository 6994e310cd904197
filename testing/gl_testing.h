// A gtest fixture for suites that share one OpenGL context (making one takes a while on
// llvmpipe). Test files only.
#pragma once

#include <gtest/gtest.h>

#include "gl/context.h"

namespace ms::gl {

class SharedGlContextTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { context_ = new GlContext(); }
  static void TearDownTestSuite() {
    delete context_;
    context_ = nullptr;
  }
  static inline GlContext* context_ = nullptr;
};

}  // namespace ms::gl
