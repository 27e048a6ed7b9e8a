(define (problem blocksworld-p07)
  (:domain blocksworld-4ops)
  (:objects
    b1 b2 b3 b4 b5 b6
  )
  (:init
    (on-table b2)
    (on-table b4)
    (on-table b1)
    (on-table b6)
    (on-table b3)
    (on b5 b6)
    (clear b2)
    (clear b4)
    (clear b1)
    (clear b5)
    (clear b3)
    (arm-empty)
  )
  (:goal (and
    (on b2 b1)
    (on b5 b2)
  ))
)
