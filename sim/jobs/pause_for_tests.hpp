// A test's fixed point in a run: with PLR_JOBS_TEST_PAUSE=<n>:<fd> in the
// environment, once this process has stored its n-th new result the engine
// writes "paused\n" to file descriptor fd and stores nothing more; the run
// hangs there until it is killed. A test that kills a run mid-way (SIGKILL,
// then resume) thus kills it with exactly n results stored, whatever the
// machine's load. For tests only; unset, it costs one getenv per process.
#pragma once

namespace plr::jobs {

// Called by the engine after each result it stores.
void pause_for_tests();

}  // namespace plr::jobs
