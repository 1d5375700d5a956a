// Storage given back: a container's own (Release) and the heap's freed pages (ReturnFreedMemory).
#pragma once

#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace selfcal {

// Frees a container's storage: clear() and assigning {} keep its capacity.
template <typename Container>
void Release(Container& container) {
  Container().swap(container);
}

// Gives the pages of freed blocks back to the system. glibc keeps what a thread's arena freed
// resident for the next allocation; after a phase that freed hundreds of megabytes the next phase
// does not allocate in the same sizes, and the process would hold both.
inline void ReturnFreedMemory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

}  // namespace selfcal
