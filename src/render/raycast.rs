//! Renderer v0.
