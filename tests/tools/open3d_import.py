"""Open3D for the interop tests, or a visible skip: Debian's python3-open3d under /usr/bin/python3.
Scripts in this folder import it as `from open3d_import import open3d_or_skip`."""
import sys

SKIP = 77  # CTest SKIP_RETURN_CODE


def open3d_or_skip():
    """Returns the open3d module with its log limited to errors; prints SKIP and exits 77 if it
    cannot be imported (ImportError, or a broken binary module)."""
    try:
        import open3d as o3d
    except Exception as e:
        print(f"SKIP: open3d is not importable with {sys.executable}: {e}")
        sys.exit(SKIP)
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    return o3d
