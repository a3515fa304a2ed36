// stdio streams over what `weaver serve` answers from and into: a query of
// `weaver query` reads its points from a FILE* and prints to one, and here
// those are a request's body and the response (held, or sent as written).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "serve/http.h"

namespace weaver::serve {

// Writes append to *s, up to cap bytes (the rest is dropped: a batch of a
// million bad lines reports one).  Null if the stream cannot be made.
std::FILE* string_stream(std::string* s, size_t cap = SIZE_MAX);
// Writes go to sink (in pieces of a 256 KiB buffer); *written counts them.
std::FILE* sink_stream(BodySink* sink, uint64_t* written);
// Reads a POST body of points as text lines: lines as they are, or a JSON
// array ([[x, y, z], ...]) turned into lines as it is read, without a copy
// of the body.  body must outlive the stream.
std::FILE* points_stream(const std::string& body);

}  // namespace weaver::serve
