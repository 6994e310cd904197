// --gl-backend, for the commands that open an OpenGL context of their own (sweep, synth,
// evaluate): MS_OPTION(type, name, default, flag, help, bound). Included by gl/context.h only
// (no include guard on purpose).

MS_OPTION(GlBackend, gl_backend, GlBackend::kAuto, "gl-backend",
          "OpenGL through EGL: auto (GPU device, else Mesa surfaceless), device or surfaceless",
          AnyValue())
