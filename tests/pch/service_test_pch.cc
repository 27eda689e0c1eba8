// The translation unit that builds the precompiled service-test headers.
