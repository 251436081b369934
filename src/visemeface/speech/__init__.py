"""visemeface.speech"""
