// pdyn/host/export.hpp — which of the host library's symbols its users
// (pdyn's programs, the Python module, the viewer) may link against.
//
// The host library is compiled with hidden visibility, as the kernel is
// (pdyn/export.hpp): only what its public headers mark PDYN_HOST_API is in
// its dynamic symbol table; the loaders, builders and writers' helpers in
// host/src stay inside it.
#pragma once

#if defined(__GNUC__) || defined(__clang__)
/// Marks a class (its members, vtable and type information) or a function
/// as part of the host library's interface.
#define PDYN_HOST_API __attribute__((visibility("default")))
#else
#define PDYN_HOST_API
#endif
