// pdyn/export.hpp — which of the kernel's symbols a plugin may link against.
//
// The kernel library is compiled with hidden visibility (-fvisibility=hidden,
// as the plugins are): only what is marked PDYN_API is in its dynamic symbol
// table. That is the SDK — every class and function these headers declare
// that the library defines, and the type information of every interface a
// plugin implements, so that dynamic_cast and exceptions work across the
// library boundary. Everything else (the library's own helpers, the
// instantiations of standard, Eigen and fmt templates) stays inside it:
// a smaller table to resolve at load time, and nothing a plugin could come
// to depend on by accident. tests/kernel/check_sdk.py keeps the exported
// list (tests/kernel/kernel_exports.txt): a symbol may be added, never lost
// without an ABI bump (version.hpp).
#pragma once

#if defined(__GNUC__) || defined(__clang__)
/// Marks a class (its members, vtable and type information) or a function
/// as part of the kernel's binary interface.
#define PDYN_API __attribute__((visibility("default")))
#else
#define PDYN_API
#endif
