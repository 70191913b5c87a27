//! brdf (stub)
