"""Training tooling for com.mocap.imu: motion data -> synthetic IMU -> pose model -> ONNX."""

MODEL_FPS = 60
