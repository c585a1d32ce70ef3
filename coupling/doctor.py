def doctor(as_json=False): return 0
