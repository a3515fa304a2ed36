// The query engine as weaver serve calls it: an ApiQuery (every value parsed
// by the service) run as `weaver query` runs the same question, its answer
// as JSON.  The words of the query are made here from the typed values:
// none is a client's string.
#pragma once

#include "serve/service.h"

namespace weaver::cli {

serve::QueryRunner serve_query_runner();

}  // namespace weaver::cli
