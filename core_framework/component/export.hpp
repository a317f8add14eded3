// How a component's source makes it both an executable and a shared library:
//
//   RSCA_COMPONENT(MyComponent)
//
// defines the factory a component host looks up (kFactorySymbol) and, unless the source is
// compiled with RSCA_COMPONENT_LIBRARY (the shared-library build), the executable's main. The
// shared library links no rsca library: the component host that loads it provides the runtime,
// so every component of a host shares one runtime, one DDS participant and one logger setup.
#pragma once

#include <memory>

#include "component/runtime.hpp"

#ifdef RSCA_COMPONENT_LIBRARY
#define RSCA_COMPONENT_DETAIL_MAIN(Class)
#else
#define RSCA_COMPONENT_DETAIL_MAIN(Class)                                                          \
  int main(int argc, char **argv) {                                                                \
    ::rsca::component::serve_forks_if_asked(argc, argv, ::rsca::process::kForkServerReady);        \
    return ::rsca::component::run<Class>(argc, argv);                                              \
  }
#endif

#define RSCA_COMPONENT(Class)                                                                      \
  extern "C" void rsca_component_factory(::rsca::component::Factory *out) {                        \
    *out = [](const ::rsca::component::Context &context) {                                         \
      return std::make_unique<Class>(context);                                                     \
    };                                                                                             \
  }                                                                                                \
  RSCA_COMPONENT_DETAIL_MAIN(Class)
