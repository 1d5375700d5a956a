// Frees a container's storage: clear() and assigning {} keep its capacity.
#pragma once

namespace selfcal {

template <typename Container>
void Release(Container& container) {
  Container().swap(container);
}

}  // namespace selfcal
