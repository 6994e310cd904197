// Checkpoints of `manisweep refine` (docs/design/refine.md "Checkpoints"): beside the output mesh
// O,
//   O.checkpoint.ply           the mesh as it stands (faces included: remeshing changes them)
//   O.checkpoint.accepted.ply  the last accepted vertices (backtracking), when there are any
//   O.checkpoint.json          the rest of RefineState, and the options it was made with
// and, once finished, O.done.json (below).
// each written atomically, the JSON last, so a checkpoint is whole or absent. Doubles are
// written exactly (binary PLY, round-trip JSON), so a resumed run ends with the same mesh.
#pragma once

#include <optional>
#include <string>

#include "mesh/mesh.h"
#include "refine/refiner.h"

namespace ms {

struct RefineCheckpoint {
  Mesh mesh;
  RefineState state;
};

// `fingerprint` names what the checkpoint is valid for (input, mesh and options).
void WriteRefineCheckpoint(const std::string& output, const Mesh& mesh, const RefineState& state,
                           const std::string& fingerprint);

// The checkpoint beside `output`, or nothing if there is none. Throws InputError if it is
// unreadable or was made for another fingerprint (naming what differs).
std::optional<RefineCheckpoint> ReadRefineCheckpoint(const std::string& output,
                                                     const std::string& fingerprint);

// Removes the checkpoint files (after a refinement that finished).
void RemoveRefineCheckpoint(const std::string& output);

// A finished refinement's record beside the output O, O.done.json: the fingerprint (which
// should name the starting mesh's content), O's size and content hash, the options and the
// iterations of the process that finished it (the run report plots them). `--resume` on a
// finished run skips the refinement when RefineIsDone says the output is that record's.
void WriteRefineDone(const std::string& output, const std::string& fingerprint,
                     const RefineStats& stats, const OptionValues& options);
// O.done.json's path.
std::string RefineDonePath(const std::string& output);
bool RefineIsDone(const std::string& output, const std::string& fingerprint);

}  // namespace ms
