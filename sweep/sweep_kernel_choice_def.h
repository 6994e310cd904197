// --kernel, for the commands that sweep (reconstruct, sweep, worker):
// MS_OPTION(type, name, default, flag, help, bound). Included by sweep/sweep_kernel_factory.h
// only (no include guard on purpose).

MS_OPTION(std::string, kernel, "auto", "kernel",
          "sweep kernel: auto (glsl on a GPU, else cpu), glsl (OpenGL 4.3 through EGL), cpu "
          "(the fast CPU kernel), reference (the exact C++ reference, slow); a worker also "
          "takes replay (hand back a recorded run's points, --replay.run)",
          AnyValue())
