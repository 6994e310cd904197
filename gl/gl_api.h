// The raw OpenGL API for .cc files only (never include this from a public header): core-profile
// prototypes from <GL/glcorearb.h>, exported by glvnd's libOpenGL, so no loader is needed.
// Error helpers shared by the gl/ implementation and by GL code built on top of it.
#pragma once

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>

#include <string>

namespace ms::gl {

// "GL_INVALID_OPERATION" for an error code.
std::string GlErrorName(GLenum error);
// Throws InternalError("<what>: GL_..." ) if glGetError() reports anything (drains the queue).
void CheckGlError(const char* what);

}  // namespace ms::gl
