//! Walkthrough server of sightline (SPEC §9): HTTP API, WebSocket walk sessions with
//! PVS prefetch, and the embedded browser viewer.
