//! Images: linear RGB buffers and PNG output.
