// The translation unit that builds the precompiled test headers.
