(define (problem blocksworld-p08)
  (:domain blocksworld-4ops)
  (:objects
    b1 b2 b3 b4 b5 b6
  )
  (:init
    (on-table b5)
    (on b2 b5)
    (on b6 b2)
    (on b1 b6)
    (on b3 b1)
    (on b4 b3)
    (clear b4)
    (arm-empty)
  )
  (:goal (and
    (on b1 b4)
    (on b3 b1)
    (on b5 b6)
  ))
)
