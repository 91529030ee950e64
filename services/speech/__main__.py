import sys

from services.speech.main import main

sys.exit(main())
