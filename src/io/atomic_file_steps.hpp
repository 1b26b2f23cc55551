// The tests' seam into OutputSet::commit: a function called at every step a kill could
// interrupt, with the step's number:
//   1..n      before writing the n-th temporary
//   50        the journal written under its temporary name, not yet in place
//   51        the journal in place (the commit point), nothing renamed yet
//   100 + i   before the i-th rename, then each removal; after the last, before the journal goes
// A test forks, sets the hook to kill the child at one step, and checks what the folder holds.
#pragma once

namespace lmcal::detail {
extern void (*commit_step_hook)(int step);
}
