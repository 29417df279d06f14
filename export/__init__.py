"""ONNX export and serving entry point: ``python -m export ...`` (logic in relightnet.model.onnx_export
and relightnet.model.onnx_serving)."""
