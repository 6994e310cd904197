// Options both ends of the protocol must agree on, one line each:
//   MS_OPTION(type, name, default, flag, help, bound)
// Top-level flags. Not a group of their own: the coordinator's and the worker's option lists
// include the lines they use (coordinator/scheduler_options_def.h, worker/worker_options_def.h),
// so each is declared once. No include guard on purpose.

#ifdef MS_LINK_HEARTBEAT_OPTIONS
// A peer silent for liveness x interval is presumed gone (a worker dead, or the coordinator).
MS_OPTION(double, heartbeat_interval_s, 1.0, "heartbeat-interval",
          "seconds between heartbeats, both ways (give the coordinator and its workers the same "
          "value)",
          InRange(0.01, 3600))
MS_OPTION(int, liveness, 5, "liveness",
          "a peer (a worker, or the coordinator) silent for this many heartbeat intervals is "
          "presumed gone",
          InRange(2, 1000))
#endif

#ifdef MS_LINK_MESSAGE_SIZE_OPTION
// A job carries the mesh the camera sees (24 bytes per vertex, 12 per face: a 1M-face visible
// mesh is ~18 MiB); protobuf's own limit is 2 GiB.
MS_OPTION(double, max_message_mb, 64, "max-message-mb",
          "largest protocol message in MiB (jobs carry the visible mesh; give the coordinator "
          "and its workers the same value); larger ones are logged and dropped",
          InRange(0.0625, 2048))
#endif
