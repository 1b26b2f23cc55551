// The public API's symbol visibility. A shared liblmcal is built with hidden visibility
// (LMCAL_SHARED): only what the public headers declare, in `namespace LMCAL_API lmcal`, is
// exported; the rest stays inside the library. Harmless in a static build.
#pragma once

#if defined(__GNUC__) || defined(__clang__)
#define LMCAL_API [[gnu::visibility("default")]]
#else
#define LMCAL_API
#endif
