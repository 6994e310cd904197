// The table written by embed_shaders.cmake. Only shaders.cc reads it.
#pragma once

namespace ms::shaders::internal {

struct EmbeddedShader {
  const char* name;
  const char* source;
};

extern const EmbeddedShader kEmbeddedShaders[];
extern const int kNumEmbeddedShaders;

}  // namespace ms::shaders::internal
