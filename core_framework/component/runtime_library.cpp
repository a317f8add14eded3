// librsca_runtime.so: the component runtime (rsca_component, whole) as one shared library, for
// component executables built outside the tree against an installed rsca. It has no code of its
// own; CMake wants a source for a library.
