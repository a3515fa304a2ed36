/* weaver's C API: the library API of weaver.h for C, Fortran (through
 * ISO_C_BINDING) and Python (ctypes).  Every function that can fail
 * returns 0 on success and -1 on an error, whose text weaver_last_error()
 * gives; iterators' next functions return 1 (an item), 0 (the end) or -1.
 * Coordinates are ticks; weaver_units gives metres per tick and the origin.
 * One weaver_db per thread. */
#ifndef WEAVER_C_H_
#define WEAVER_C_H_

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct weaver_db weaver_db;
typedef struct weaver_element_iter weaver_element_iter;
typedef struct weaver_node_iter weaver_node_iter;

typedef struct {
  int32_t inside; /* 0: outside the domain, the rest is zero */
  int32_t level;
  uint64_t element;
  uint32_t corner[3];
  uint32_t edge;
  float vp, vs, rho;
} weaver_hit;

typedef struct {
  uint64_t id;
  uint32_t corner[3];
  uint32_t edge;
  int32_t level;
  int32_t pad_;
  uint64_t nodes[8]; /* corners 0..7, x fastest; zeros before extraction */
  float vp, vs, rho;
} weaver_element;

typedef struct {
  uint64_t id;
  uint32_t at[3];
  int32_t kind; /* 0 anchored, 1 edge-dangling, 2 face-dangling */
  int32_t anchor_count;
  int32_t pad_;
  uint64_t anchors[4];
} weaver_node;

typedef struct {
  int32_t dx, dy, dz; /* the direction crossed */
  int32_t pad_;
  uint64_t element;
} weaver_neighbor;

/* Opens a database read-only within memory_bytes (0: 256 MiB); NULL on
 * failure, with the reason in error (error_size bytes, may be 0). */
weaver_db* weaver_open(const char* path, uint64_t memory_bytes, char* error, size_t error_size);
/* The same, answering a weaver_locate of 16384 points or more on `threads`
 * threads (1: the calling thread alone, as weaver_open; 0: one a core),
 * memory_bytes shared among them.  A program with threads of its own, a
 * weaver_db each, keeps 1. */
weaver_db* weaver_open_threads(const char* path, uint64_t memory_bytes, int threads, char* error,
                               size_t error_size);
void weaver_close(weaver_db* db);
const char* weaver_last_error(const weaver_db* db);

uint64_t weaver_element_count(const weaver_db* db);
uint64_t weaver_node_count(const weaver_db* db);
int weaver_has_material(const weaver_db* db);
/* Metres per tick, and origin[3] in metres. */
double weaver_units(const weaver_db* db, double origin[3]);

/* n points as xyz[3*i..3*i+2]; out[i] answers point i. */
int weaver_locate(weaver_db* db, const uint32_t* xyz, size_t n, weaver_hit* out);
int weaver_element_get(weaver_db* db, uint64_t id, weaver_element* out);
int weaver_node_get(weaver_db* db, uint64_t id, weaver_node* out);
/* *found = 0 if no node sits at the point. */
int weaver_node_at(weaver_db* db, const uint32_t xyz[3], int* found, uint64_t* id);
/* kinds: 1 faces, 2 edges, 4 corners, or a sum.  Writes up to capacity
 * neighbours and their total in *count (call again with more room if
 * *count > capacity). */
int weaver_neighbors(weaver_db* db, uint64_t element, int kinds, weaver_neighbor* out,
                     size_t capacity, size_t* count);

weaver_element_iter* weaver_elements(weaver_db* db, uint64_t first);
int weaver_element_next(weaver_element_iter* it, weaver_element* out);
void weaver_element_iter_free(weaver_element_iter* it);
weaver_node_iter* weaver_nodes(weaver_db* db);
int weaver_node_next(weaver_node_iter* it, weaver_node* out);
void weaver_node_iter_free(weaver_node_iter* it);

#ifdef __cplusplus
}
#endif

#endif /* WEAVER_C_H_ */
