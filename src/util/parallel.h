// Fork-join for a few equal shares of one piece of work: share 0 runs on the
// calling thread, the others on threads of their own, and the call returns
// when all are done.  For work big enough that starting a thread is noise
// (balance's chunks of parents and its sorts).
#pragma once

#include <thread>
#include <vector>

#include "schema/status.h"

namespace weaver {

// Runs work(0) .. work(shares - 1) at once; the first error by share number.
template <class Work>
Status run_shares(int shares, const Work& work) {
  std::vector<Status> status(static_cast<size_t>(shares));
  std::vector<std::thread> threads;
  for (int i = 1; i < shares; ++i) threads.emplace_back([&, i] { status[i] = work(i); });
  status[0] = work(0);
  for (std::thread& t : threads) t.join();
  for (Status& s : status) WEAVER_RETURN_IF_ERROR(s);
  return Status::Ok();
}

}  // namespace weaver
